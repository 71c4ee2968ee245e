"""``python -m gcs_tools.studies NAME [ARGS]``: run one study (see :mod:`gcs_tools.studies`)."""

from __future__ import annotations

import importlib
import sys

from gcs_tools.studies import STUDIES


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in STUDIES:
        out = sys.stdout if not argv or argv[0] in ("-h", "--help") else sys.stderr
        if argv and argv[0] not in ("-h", "--help"):
            print(f"gcs_tools.studies: unknown study {argv[0]!r}", file=out)
        print("usage: python -m gcs_tools.studies NAME [ARGS]   (NAME --help for its options)\n\nstudies:", file=out)
        for name, (_, what) in STUDIES.items():
            print(f"  {name:14s} {what}", file=out)
        return 0 if out is sys.stdout else 2
    name, rest = argv[0], argv[1:]
    module, _ = STUDIES[name]
    # imported by name (not run as __main__) so that the sweeps' worker processes can import
    # what the study hands them; each study's main() reads its arguments from sys.argv
    study = importlib.import_module(f"gcs_tools.studies.{module}")
    sys.argv = [f"python -m gcs_tools.studies {name}", *rest]
    try:
        code = study.main()
    except SystemExit as exc:
        if exc.code is None or isinstance(exc.code, int):
            return exc.code or 0
        print(exc.code, file=sys.stderr)
        return 1
    return code or 0


if __name__ == "__main__":
    sys.exit(main())
