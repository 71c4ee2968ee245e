"""Child-process entry point: run one probe function and write its figures as JSON.

Invoked by :func:`benchmarks.harness.run_probe` as
``python -m benchmarks._worker --module M --func F --params JSON --out FILE``.
The result file holds ``{"figures": {...}}`` or ``{"error": "...", "traceback": "..."}``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import traceback
from pathlib import Path


def _resolve(module: str, qualname: str):
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def _check_figures(figs) -> dict:
    if not isinstance(figs, dict):
        raise TypeError(f"a probe must return a dict of figures, got {type(figs).__name__}")
    out = {}
    for k, v in figs.items():
        if not isinstance(k, str):
            raise TypeError(f"figure names must be str, got {k!r}")
        if hasattr(v, "item") and not isinstance(v, (str, bytes)):
            v = v.item()  # numpy scalar
        if v is not None and not isinstance(v, (bool, int, float, str)):
            raise TypeError(f"figure {k!r} has unsupported type {type(v).__name__}")
        if isinstance(v, float) and not math.isfinite(v):
            raise ValueError(f"figure {k!r} is not finite: {v}")
        out[k] = v
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks._worker")
    ap.add_argument("--module", required=True)
    ap.add_argument("--func", required=True)
    ap.add_argument("--params", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    out = Path(a.out)
    try:
        func = _resolve(a.module, a.func)
        figs = _check_figures(func(**json.loads(a.params)))
    except Exception as exc:  # reported to the parent, which records the probe as failed
        out.write_text(json.dumps({
            "error": f"{type(exc).__name__}: {exc}",
            "traceback": traceback.format_exc(),
        }))
        return 2
    out.write_text(json.dumps({"figures": figs}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
