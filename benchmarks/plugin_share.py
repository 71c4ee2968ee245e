"""Controller plug-ins against the built-in strategy in one warm process, timed in CPU time.

``python -m benchmarks.plugin_share [--duration S] [--repeat N] [--cases a,b,...] [--markdown FILE]``

The ``plugins`` benchmark (``python -m benchmarks --only plugins``) runs every probe in fresh
processes with an empty numba cache, so each probe pays a cold compile of the step loop first
(minutes on a busy 2-core machine). This is the quick companion for a machine that is busy or
for comparing source trees (run it with ``PYTHONPATH`` on each tree, the tree's cache warm): one
process flies the helix (1 kHz physics, 500 Hz control, full sensing chain) with the built-in
``pid`` strategy and with the plug-ins, alternated ``--repeat`` times, and reports each one's
real-time factor in wall time and in the process's CPU time, and its CPU-time factor as a share
of the built-in's, paired per repetition (the median of the pairs). Other processes on the
machine disturb the CPU-time figures much less than the wall-clock ones.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

#: what flies in each case, for the markdown table
WHAT = {
    "builtin-pid": "the built-in `pid` strategy (the reference)",
    "compiled-pid": "`examples.pid:PID`, the same law as a compiled kernel",
    "python-pid": "the same kernel run as plain Python (`controller.call = \"python\"`, numpy scalars throughout)",
    "trivial": "a Python controller that returns the hover thrust (hover)",
    "cascaded": "`examples.cascaded_pid:CascadedPID`, a 30-line cascaded PID in plain Python",
    "cascaded-builtins": "the same law, bit for bit, with `min(max(...))` clamps, `range(3)` loops and `math.sin` "
                         "looked up (`benchmarks.idioms`)",
    "cascaded-numpy": "the same again, reading numpy scalars from the observation's views instead of `.tolist()` "
                      "floats",
}

CASES = {
    "builtin-pid": ("helix", None, "compiled"),
    "compiled-pid": ("helix", "rig_emulator.controllers.examples.pid:PID", "compiled"),
    "python-pid": ("helix", "rig_emulator.controllers.examples.pid:PID", "python"),
    "trivial": ("hover", "benchmarks.plugins:TrivialHover", "python"),
    "cascaded": ("helix", "rig_emulator.controllers.examples.cascaded_pid:CascadedPID", "python"),
    "cascaded-builtins": ("helix", "benchmarks.idioms:CascadedPIDBuiltins", "python"),
    "cascaded-numpy": ("helix", "benchmarks.idioms:CascadedPIDNumpy", "python"),
}


def fly(name: str, duration: float):
    """(wall, CPU) real-time factors of one flight of case ``name``."""
    from rig_emulator.api import simulate

    scenario, controller, call = CASES[name]
    c0 = time.process_time()
    r = simulate(scenario, strategy="pid", duration=duration, seed=0, controller=controller,
                 overrides={"controller.call": call})
    return r.sim_time_s / r.wall_time_s, r.sim_time_s / (time.process_time() - c0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.plugin_share", description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=10.0, help="simulated s per flight (default %(default)s)")
    ap.add_argument("--repeat", type=int, default=3, help="flights per case, alternated (default %(default)s)")
    ap.add_argument("--cases", default=",".join(CASES), help="comma list of %(default)s")
    ap.add_argument("--markdown", metavar="FILE",
                    help="also write the table as a documentation page: the command, the machine and its load above it")
    args = ap.parse_args(argv)
    names = args.cases.split(",")
    if "builtin-pid" not in names:
        names.insert(0, "builtin-pid")
    for n in names:
        if n not in CASES:
            ap.error(f"unknown case {n!r}; cases: {', '.join(CASES)}")
    t_start = time.perf_counter()
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    for n in names:  # compile, or load the cache
        fly(n, 0.2)
    print(f"compiled or loaded in {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    runs: dict = {n: [] for n in names}
    for k in range(args.repeat):
        for n in (names if k % 2 == 0 else names[::-1]):
            runs[n].append(fly(n, args.duration))
    print(f"helix {args.duration:g} s x {args.repeat}, load average {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    ref = runs["builtin-pid"]
    rows = []
    for n in names:
        wall = statistics.median(w for w, _ in runs[n])
        cpu = statistics.median(c for _, c in runs[n])
        shares = [c / rc for (_, c), (_, rc) in zip(runs[n], ref)]
        share = statistics.median(shares)
        print(f"{n:14s} real-time factor {wall:7.1f}x wall, {cpu:7.1f}x CPU; share of the built-in's {share:.3f}")
        # the helix's controller runs at 500 Hz: CPU time a call above the built-in's
        extra = "-" if n == "builtin-pid" else f"{(1.0 / cpu - 1.0 / statistics.median(c for _, c in ref)) / 500.0 * 1e6:.1f} us"
        rows.append(f"| `{n}` | {WHAT[n]} | {wall:.0f}x | {cpu:.0f}x | {share:.2f} ({min(shares):.2f}-{max(shares):.2f}) "
                    f"| {extra} |")
    if args.markdown:
        from gcs_tools.studies.page import command_line, machine

        argv = ["python -m benchmarks.plugin_share", *sys.argv[1:]]
        text = (f"Written by `{command_line(argv)}` in {time.perf_counter() - t_start:.0f} s on {machine()}, "
                f"load average {load0:.1f} at the start and {os.getloadavg()[0]:.1f} at the end: the helix, "
                f"{args.duration:g} s simulated a flight, {args.repeat} flights a case alternated in one warm process. "
                "Real-time factors are medians over the flights; the share is the CPU-time factor over the "
                "built-in's of the same round (median, min-max); the extra CPU a call is what a controller call "
                "(500 Hz) costs above the built-in's, from the medians. The built-in's 1 kHz physics step costs "
                f"{1e3 / statistics.median(c for _, c in ref):.1f} us of CPU (sensing, estimation, control and log "
                "included).\n\n"
                "| case | what flies | real-time factor (wall) | real-time factor (CPU time) | share of the built-in's "
                "| extra CPU a call |\n"
                "| --- | --- | --- | --- | --- | --- |\n" + "\n".join(rows) + "\n")
        with open(args.markdown, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
