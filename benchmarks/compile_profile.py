"""Where numba's cold compile of the step loop spends its time (issue 14).

``python -m benchmarks.compile_profile [--scenario hover] [--top 25] [--json FILE]`` runs one
headless ``simulate`` (0.1 s) in **this** process with an empty numba cache (a fresh
temporary ``HILMS_NUMBA_CACHE``, removed afterwards) and records numba's own compile events
(``numba.core.event``: ``numba:compile`` per dispatcher and signature, ``numba:run_pass`` per
compiler pass). It prints:

* the wall and CPU time of the whole cold call (what a user waits for on a first run);
* per compiled function (dispatcher): the time of its own compiler passes, callees'
  compilations excluded ("self"), and with them ("total"); how many signatures each
  dispatcher was compiled for (a function compiled for several argument types, e.g. a
  literal constant argument, pays several times);
* per compiler pass, its self time summed over all functions (type inference, inlining,
  lowering to LLVM IR and LLVM's optimisation and code generation show up here);
* the time outside any compile event (imports, cache writes, the run itself).

Nothing here asserts; the figures are noisy on a shared machine: compare runs made back to
back and quote CPU time next to wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from collections import defaultdict


def _profile(scenario: str, duration: float) -> dict:
    from numba.core import event as ev

    class Recorder(ev.Listener):
        def __init__(self):
            self.buffer = []

        def on_start(self, event):
            self.buffer.append((time.perf_counter(), True, event))

        def on_end(self, event):
            self.buffer.append((time.perf_counter(), False, event))

    rec = Recorder()
    ev.register("numba:compile", rec)
    ev.register("numba:run_pass", rec)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    from rig_emulator.api import simulate

    t_import = time.perf_counter() - wall0
    simulate(scenario, duration=duration)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    ev.unregister("numba:compile", rec)
    ev.unregister("numba:run_pass", rec)

    def label(e) -> str:
        d = e.data
        if e.kind == "numba:compile":
            disp = d["dispatcher"]
            return f"{disp.py_func.__module__}.{disp.py_func.__qualname__}"
        return d["name"].split(" [")[0]

    fn_own = defaultdict(float)  # compiler-pass time of the function itself (callees' compiles excluded)
    fn_self = defaultdict(float)
    fn_total = defaultdict(float)
    fn_sigs = defaultdict(set)
    pass_self = defaultdict(float)
    stack = []  # [label, kind, start, child time]
    in_compile = 0.0
    for ts, start, e in rec.buffer:
        if start:
            stack.append([label(e), e.kind, ts, 0.0, e])
            continue
        name, kind, t0, child, e0 = stack.pop()
        total = ts - t0
        if stack:
            stack[-1][3] += total
        else:
            in_compile += total
        if kind == "numba:compile":
            fn_total[name] += total
            fn_self[name] += total - child
            fn_sigs[name].add(str(e0.data.get("args")))
        else:
            pass_self[name] += total - child
            fn_own[f"{e0.data['module']}.{e0.data['qualname']}"] += total - child
    return {
        "scenario": scenario,
        "wall_s": wall,
        "cpu_s": cpu,
        "import_s": t_import,
        "in_compile_events_s": in_compile,
        "functions": sorted(
            ({"name": n, "self_s": fn_own.get(n, 0.0) + fn_self[n], "total_s": fn_total[n],
              "signatures": len(fn_sigs[n])} for n in fn_self),
            key=lambda r: -r["self_s"],
        ),
        "passes": sorted(({"name": n, "self_s": s} for n, s in pass_self.items()), key=lambda r: -r["self_s"]),
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.compile_profile", description=__doc__.split("\n\n")[0])
    p.add_argument("--scenario", default="hover")
    p.add_argument("--duration", type=float, default=0.1)
    p.add_argument("--top", type=int, default=25)
    p.add_argument("--json", help="also write the figures to this JSON file")
    p.add_argument("--cache", help="numba cache directory to compile into and keep (must be empty; default: a "
                                   "temporary one, removed)")
    args = p.parse_args(argv)
    if "rig_emulator._jit" in sys.modules:
        raise SystemExit("run in a fresh process: the numba cache directory is chosen at import")
    cache = args.cache or tempfile.mkdtemp(prefix="hilms-compile-profile-")
    if args.cache and os.path.isdir(cache) and os.listdir(cache):
        raise SystemExit(f"--cache {cache}: not empty (the profile needs a cold cache)")
    os.environ["HILMS_NUMBA_CACHE"] = cache
    try:
        out = _profile(args.scenario, args.duration)
    finally:
        if not args.cache:
            shutil.rmtree(cache, ignore_errors=True)
    print(f"cold {args.scenario} {args.duration:g} s: wall {out['wall_s']:.1f} s, CPU {out['cpu_s']:.1f} s "
          f"(imports {out['import_s']:.1f} s wall; inside numba compile events {out['in_compile_events_s']:.1f} s)")
    print(f"\nfunctions by self compile time (top {args.top} of {len(out['functions'])}):")
    print(f"{'self s':>8} {'total s':>8} {'sigs':>4}  function")
    for r in out["functions"][: args.top]:
        print(f"{r['self_s']:8.2f} {r['total_s']:8.2f} {r['signatures']:4d}  {r['name']}")
    print(f"\ncompiler passes by self time (top {args.top}):")
    for r in out["passes"][: args.top]:
        print(f"{r['self_s']:8.2f}  {r['name']}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
