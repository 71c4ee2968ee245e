"""Reading a user's text file (mission, parameter list) with errors that name the file and line.

:func:`read_text` returns the file's text, or raises ``error(source, line, reason)`` (the
caller's exception class, e.g. ``MissionFileError``) when it cannot be read, is not UTF-8 or
holds a NUL byte (a binary file given by mistake), with the line where the bad byte is.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable


def read_text(path, error: Callable[[str, int | None, str], Exception]) -> str:
    source = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise error(source, None, f"cannot read: {exc.strerror}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(source, data[: exc.start].count(b"\n") + 1, "not UTF-8 text") from None
    if "\x00" in text:
        raise error(source, text[: text.index("\x00")].count("\n") + 1, "NUL byte: not a text file")
    return text
