"""The markdown page a study writes with ``--markdown FILE``: its tables under a line that says
the command that made them, how long it took and on what machine.

A study prints its tables as it measures them; :class:`Page` keeps what it prints (or a
markdown version of it, where the study's terminal output is plain text) and writes the file
at the end, so that the documentation includes the study's own output rather than figures
typed from it (``--8<-- "generated/study-....md"`` in docs/explanation/).
"""

from __future__ import annotations

import os
import platform
import shlex
import sys
import time
from pathlib import Path


def cpu_model() -> str | None:
    """The CPU's model name from /proc/cpuinfo (None where there is none)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def machine() -> str:
    """The CPU model, its core count and the Python version, in words."""
    cpu = cpu_model() or platform.processor() or platform.machine()
    return f"{cpu} x{os.cpu_count()}, Python {platform.python_version()}"


def _load() -> str:
    return f"{os.getloadavg()[0]:.1f}" if hasattr(os, "getloadavg") else "?"


def span(values: list[float], digits: int) -> str:
    """``lo-hi`` of ``values`` at ``digits`` decimals (one number where both round alike; ``lo to hi``
    where ``lo`` is negative, which a hyphen would hide)."""
    lo, hi = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    if lo == hi:
        return lo
    return f"{lo} to {hi}" if lo.startswith("-") else f"{lo}-{hi}"


def command_line(argv: list[str] | None = None) -> str:
    """The study's command as the user typed it (``gcs_tools.studies``' ``main`` puts
    ``python -m gcs_tools.studies NAME`` in ``sys.argv[0]``)."""
    argv = list(sys.argv if argv is None else argv)
    return " ".join([argv[0], *(shlex.quote(a) for a in argv[1:])])


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


class Page:
    """Prints a study's output and keeps it for ``--markdown FILE``.

    ``what``: one sentence on what the tables measure (the page's first line after the command);
    ``workers``: the worker processes the study's runs went to (``None``: the study's default).
    """

    def __init__(self, path: str | None, what: str = "", workers: int | None = None):
        self.path = Path(path) if path else None
        self.what = what
        self.workers = workers
        self.lines: list[str] = []
        self.command = command_line()
        self._wall0 = time.perf_counter()
        self._load0 = _load()

    def print(self, *parts, md: str | None = None) -> None:
        """Print ``parts`` as ``print`` does (flushed: long studies print row by row) and keep ``md``
        (default: the printed line) for the page; ``md=""`` keeps nothing."""
        text = " ".join(str(p) for p in parts)
        print(text, flush=True)
        self.page(text if md is None else md)

    def page(self, md: str) -> None:
        """Keep ``md`` for the page only (a markdown form of what the terminal got as plain text)."""
        if md:
            self.lines.append(md)

    def blank(self) -> None:
        """An empty line, on the terminal and on the page (markdown needs one between a list and a table)."""
        print(flush=True)
        self.lines.append("")

    def header(self) -> str:
        wall = time.perf_counter() - self._wall0
        workers = "" if self.workers is None else \
            f" with {self.workers} worker process{'es' if self.workers != 1 else ''}"
        return (f"Written by `{self.command}`: {_duration(wall)} wall{workers} on {machine()}, "
                f"load average {self._load0} at the start and {_load()} at the end (other work shares "
                "the cores)." + (f" {self.what}" if self.what else ""))

    def write(self) -> None:
        """Write the page to ``--markdown``'s file, if one was given (the whole file at once)."""
        if self.path is None:
            return
        from protocol.atomic_file import atomic_write_text

        body = "\n".join(self.lines).strip("\n")
        atomic_write_text(self.path, self.header() + "\n\n" + body + "\n")
        print(f"wrote {self.path}", file=sys.stderr)
