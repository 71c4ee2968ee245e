"""Reading a documentation page's table in a test: the rows of the first table under a heading.

Tests that check a shipped file against the table that documents it (the flight stacks'
parameter files against docs/how-to/flight-stacks.md) read the table with this one function.
"""

from __future__ import annotations

import re
from pathlib import Path

#: the repository's docs/ folder (tests run from a checkout)
DOCS = Path(__file__).resolve().parents[2] / "docs"


def table_rows(page: str | Path, heading: str, row: str) -> dict[str, tuple[str, ...]]:
    """name -> the other groups of ``row`` (a regular expression whose first group is the row's
    name) for every line of ``page`` (a path, or one relative to docs/) that matches it between
    ``heading`` and the next heading. A name listed twice fails."""
    path = Path(page)
    text = (path if path.is_absolute() else DOCS / path).read_text()
    section = text[text.index(heading):]
    end = section.find("\n#", len(heading))
    section = section if end < 0 else section[:end]
    rows: dict[str, tuple[str, ...]] = {}
    for line in section.splitlines():
        m = re.match(row, line)
        if m:
            assert m[1] not in rows, f"{m[1]} twice in the table under {heading!r} of {page}"
            rows[m[1]] = m.groups()[1:]
    return rows
