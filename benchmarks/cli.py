"""Command line of the benchmark suite (``python -m benchmarks --help``)."""

from __future__ import annotations

import argparse
import os
import signal
import sys

from .harness import BenchmarkError, render_report, run_suite, write_json

DEFAULT_REPEAT = 5
QUICK_REPEAT = 2


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks",
        description="Run the hilms-sil benchmarks; every probe runs in a fresh subprocess, "
                    "figures are medians over repetitions, ratios are against references "
                    "measured in the same run.",
    )
    ap.add_argument("--repeat", type=int, default=None, metavar="N",
                    help=f"fresh-process repetitions per probe (default {DEFAULT_REPEAT}, "
                         f"{QUICK_REPEAT} with --quick)")
    ap.add_argument("--quick", action="store_true",
                    help="short smoke run: small durations, fewer repetitions; figures are noisy")
    ap.add_argument("--only", action="append", metavar="NAME", default=None,
                    help="run only this benchmark (repeatable, or comma-separated)")
    ap.add_argument("--out", default="bench-results.json", metavar="FILE",
                    help="JSON results file (default: bench-results.json in the current directory)")
    ap.add_argument("--timeout", type=float, default=900.0, metavar="S",
                    help="limit per probe subprocess, seconds (default 900)")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="many-rigs: also run each sweep on this Dask cluster (tcp://HOST:PORT, or 'local' for a "
                         "LocalCluster with one worker process per core)")
    ap.add_argument("--list", action="store_true", help="list benchmarks and their probes, then exit")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    from .suite import REGISTRY

    if args.list:
        for b in REGISTRY.benchmarks.values():
            print(f"{b.name}: {b.description}")
            for p in b.probes:
                print(f"    probe {p}: {REGISTRY.probes[p].description}")
        return 0
    if args.scheduler:
        from .many_rigs import SCHEDULER_ENV

        os.environ[SCHEDULER_ENV] = args.scheduler  # the probes' subprocesses inherit it
    only = [n.strip() for item in (args.only or []) for n in item.split(",") if n.strip()]
    repeat = args.repeat if args.repeat is not None else (QUICK_REPEAT if args.quick else DEFAULT_REPEAT)
    # SIGTERM ends the run like Ctrl-C: the harness' clean-up (temporary numba caches) still runs
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    try:
        doc = run_suite(REGISTRY, only=only or None, repeat=repeat, quick=args.quick,
                        timeout=args.timeout)
    except BenchmarkError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    doc["settings"]["scheduler"] = args.scheduler
    print(render_report(doc))
    path = write_json(doc, args.out)
    print(f"\nresults written to {path}")
    failed = [n for n, e in doc["benchmarks"].items() if e["status"] != "ok"]
    return 1 if failed else 0
