"""``rig-gcs reproduce -o DIR``: the paper's experiments, figures, numbers and verdicts in one command.

Registered in :mod:`gcs_tools.cli` by :func:`add_parser`. Exit codes: 0 report written,
1 a run failed (a simulation, the rig process, the Dask cluster), 2 bad arguments.
"""

from __future__ import annotations

import json
import sys
import time

from gcs_tools.arg_types import whole_number_at_least
from gcs_tools.errors import EXIT_OK, UsageError
from gcs_tools.reproduce.experiments import NAMES


_workers = whole_number_at_least(1)
_seed = whole_number_at_least(0)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "reproduce", help="run the paper's experiments and write a report comparing them with the paper",
        description="Runs the paper's experiments headless and in parallel (hover with shocks, harmonic tracking, "
                    "frequency sweep, extra masses, line-then-helix, the 250 s altitude run, and the waypoint "
                    "rectangle flown over MAVLink), then writes DIR/report.md (our numbers next to the paper's and "
                    "a verdict on each of its claims), DIR/results.json and PNG figures. The same seed gives the "
                    "same files byte for byte. See docs/how-to/reproduce.md.")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="directory for report.md, results.json and figures")
    p.add_argument("--seed", type=_seed, default=0, help="first seed of every plant's runs: %(default)s")
    p.add_argument("--seeds", type=_workers, default=3, help="seeds per plant (SEED, SEED+1, ...): %(default)s")
    p.add_argument("--plant", action="append", metavar="AIRFRAME",
                   help="plant to run every experiment on (repeatable; default: hilms, the hardware rig, and "
                        "hilms-ideal, the ideal plant; the first one's runs give the detailed sections)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", dest="sets",
                   help="parameter override on top of every run (repeatable), e.g. smc.gain_reading=thrust")
    p.add_argument("--workers", type=_workers, help="local processes (default: one per core; 1 = in this process)")
    p.add_argument("--scheduler", metavar="ADDR", help="run the headless simulations on a Dask cluster, e.g. "
                                                       "tcp://HOST:8786 (needs pip install 'hilms-sil[cluster]')")
    p.add_argument("--only", action="append", nargs="+", metavar="NAME",
                   help=f"run only these experiments (repeatable, or comma-separated): {', '.join(NAMES)}")
    p.add_argument("--quick", action="store_true", help="shortened runs, fewer frequencies and masses: a smoke test, "
                                                        "not the reproduction")
    p.add_argument("--controller", metavar="MODULE:NAME", action="append",
                   help="compare a controller plug-in (docs/how-to/your-controller.md) with the paper's four controllers "
                        "(SMC, FLC, SMC-FLC, PID) on shocks, harmonic, sweep, masses, helix and rectangle (--only "
                        "picks among them) instead of reproducing the paper's claims: tables over the seeds, figures "
                        "and better/same/worse verdicts (repeatable, or comma-separated, for several plug-ins; "
                        "docs/how-to/compare-controllers.md)")
    p.add_argument("--strategy", default="smc-flc", choices=("smc-flc", "flc", "smc", "pid"),
                   help="with --controller: the built-in loops the plug-in keeps (default %(default)s)")
    p.add_argument("--no-progress", action="store_true", help="no progress output on stderr")
    p.add_argument("--timing", metavar="FILE.json", help="also write the run's wall-clock and CPU time to FILE "
                                                        "(never into DIR: the report stays bit-identical)")
    p.set_defaults(func=cmd_reproduce)


def _cpu_s() -> float:
    """CPU seconds of this process and its finished children (this process only where getrusage is missing)."""
    try:
        import resource
    except ImportError:  # Windows
        return time.process_time()
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def cmd_reproduce(args) -> int:
    from gcs_tools.reproduce.runner import reproduce
    from protocol.atomic_file import atomic_write_text

    only = None
    if args.only:
        only = [n.strip() for group in args.only for item in group for n in item.split(",") if n.strip()]
    if args.workers is not None and args.scheduler:
        raise UsageError("give --workers (local processes) or --scheduler (a Dask cluster), not both")
    from rig_emulator.config.loader import ConfigError, parse_override

    try:
        overrides = dict(parse_override(text) for text in args.sets)
    except ConfigError as exc:
        raise UsageError(f"--set: {exc}") from None
    from gcs_tools.reproduce.plants import PLANTS

    plants = tuple(args.plant) if args.plant else PLANTS
    t0, c0 = time.perf_counter(), _cpu_s()
    try:
        outcome = reproduce(args.output, seed=args.seed, workers=args.workers, scheduler=args.scheduler, only=only,
                            quick=args.quick, show_progress=not args.no_progress, plants=plants, seeds=args.seeds,
                            overrides=overrides, controller=args.controller,
                            strategy=args.strategy)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    from rig_emulator.sweep import shutdown_pool

    shutdown_pool()  # the sweep's warm workers end here, so their CPU time counts among the children's
    wall, cpu = time.perf_counter() - t0, _cpu_s() - c0
    from gcs_tools.reproduce.paper_data import CLAIMS
    from gcs_tools.reproduce.plants import count, verdicts

    if args.controller:
        from gcs_tools.reproduce.compare_report import raised, summary_lines

        for line in summary_lines(outcome.columns, ",".join(args.controller)):
            print(line)
        for plant, who, seed, text in raised(outcome.columns):
            print(f"warning: {who} raised on {plant}, seed {seed}, {text} (a failed run in the report)",
                  file=sys.stderr)
    for col in outcome.columns if not args.controller else []:
        k = count(col)
        print(f"{col.label}: {k['reproduced']} of {sum(k.values())} claims reproduced, {k['partly reproduced']} "
              f"partly (majority over {args.seeds} seed(s))")
    for claim, (text, where) in CLAIMS.items() if not args.controller else []:
        cells = [verdicts(col).get(claim, ("not run", []))[0] for col in outcome.columns]
        if all(c == "not run" for c in cells):
            continue
        print(" | ".join(f"{c:>17}" for c in cells) + f" : {text} ({where})")
    print("columns: " + " | ".join(col.label for col in outcome.columns))
    figures = sum(name.suffix == ".png" for name in outcome.files)
    print(f"wrote {outcome.files[0]} , results.json and {figures} figures")
    where = f"Dask cluster {args.scheduler}" if args.scheduler else "local processes"
    print(f"reproduction: {wall:.1f} s wall, {cpu:.1f} s CPU (this process and its local children), "
          f"{outcome.jobs} headless runs ({outcome.sim_seconds:.0f} simulated s) on {where}")
    if args.timing:
        atomic_write_text(args.timing, json.dumps({"wall_s": wall, "cpu_s": cpu, "headless_runs": outcome.jobs,
                                                   "simulated_s": outcome.sim_seconds, "seed": args.seed,
                                                   "quick": args.quick, "scheduler": args.scheduler,
                                                   "workers": args.workers}, indent=1) + "\n")
    return EXIT_OK
