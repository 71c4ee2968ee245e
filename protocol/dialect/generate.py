"""Regenerate ``protocol/dialect/hilms.py`` from ``hilms.xml`` with pymavlink's mavgen.

Run as ``python -m protocol.dialect.generate [output.py]``. The XML tree (``hilms.xml`` and
the vendored ``common.xml``, ``standard.xml``, ``minimal.xml``) lives next to this file, so
generation needs no network and no message_definitions checkout. The generated module is
checked in; ``tests/protocol/test_dialect.py`` regenerates it into a temporary directory and
fails on any difference.

mavgen's output also depends on the generator's own code, so the checked-in module is
reproducible for the pymavlink version in ``GENERATOR_PYMAVLINK_VERSION``.

Implements: MAVLink 2 code generation (``pymavlink.generator.mavgen``, wire protocol 2.0,
Python3 backend, XSD validation on, strict units off because N, N.m and gf are not in
mavschema.xsd's unit list).
"""

from __future__ import annotations

import contextlib
import io
import sys
from pathlib import Path

from pymavlink.generator import mavgen, mavparse

DIALECT_DIR = Path(__file__).resolve().parent
DIALECT_XML = DIALECT_DIR / "hilms.xml"
GENERATED_MODULE = DIALECT_DIR / "hilms.py"
GENERATOR_PYMAVLINK_VERSION = "2.4.50"


class GenerationError(RuntimeError):
    """mavgen rejected the dialect; the message carries mavgen's log."""


def generate(output: Path | str = GENERATED_MODULE, xml: Path | str = DIALECT_XML) -> Path:
    """Generate the Python3 MAVLink 2 module for ``xml`` into ``output``; return its path.

    mavgen writes its progress to stdout; it is captured and only shown on failure.
    """
    output = Path(output)
    xml = Path(xml)
    opts = mavgen.Opts(
        str(output),
        wire_protocol=mavparse.PROTOCOL_2_0,
        language="Python3",
        validate=True,
        strict_units=False,
    )
    log = io.StringIO()
    try:
        with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
            ok = mavgen.mavgen(opts, [str(xml)])
    except SystemExit as exc:  # mavgen calls exit() on validation errors
        raise GenerationError(f"mavgen exited ({exc.code}):\n{log.getvalue()}") from exc
    if not ok or not opts.validate:
        raise GenerationError(f"mavgen failed or could not validate {xml}:\n{log.getvalue()}")
    return output


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: optional output path, defaults to the checked-in module."""
    args = sys.argv[1:] if argv is None else argv
    out = generate(args[0]) if args else generate()
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
