"""Where numba's cold compile of the step loop spends its time.

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

``--phases`` instead splits the **CPU** time of every compiled function (numba code library)
into numba's typing, its other passes, its lowering to LLVM IR (Python), and LLVM's parsing,
function-level optimisation, module-level optimisation (after the callees are linked in) and
machine-code generation, by timing numba's own codegen methods (``CPUCodeLibrary``); see the
"Cold compile" section of docs/explanation/performance.md.

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


_PHASES = ("typing", "passes", "lower", "parse", "fopt", "mopt", "codegen", "link")


def _install_phase_hooks():
    """Time numba's compile phases per code library in CPU seconds; returns (table, signatures)."""
    from numba.core import codegen as cg, event as ev, typed_passes as tp

    table = defaultdict(lambda: defaultdict(float))  # function -> phase -> CPU s (callees excluded)
    sigs = defaultdict(set)
    stack = []  # [name, phase, start, child time]
    clock = time.process_time

    def enter(name, phase):
        stack.append([name, phase, clock(), 0.0])

    def leave():
        name, phase, t0, child = stack.pop()
        dt = clock() - t0
        table[name][phase] += dt - child
        if stack:
            stack[-1][3] += dt

    def timed(method, phase, name_of):
        def run(self, *a):
            enter(name_of(self, *a), phase)
            try:
                return method(self, *a)
            finally:
                leave()
        return run

    lib = lambda self, *a: self.name  # noqa: E731
    L = cg.CPUCodeLibrary
    L.add_ir_module = timed(L.add_ir_module, "parse", lib)  # IR text, parse, verify (fopt nested)
    L._optimize_functions = timed(L._optimize_functions, "fopt", lib)
    L._optimize_final_module = timed(L._optimize_final_module, "mopt", lib)
    L.finalize = timed(L.finalize, "link", lib)  # linking the callees in, verify (mopt, codegen nested)
    cg.JITCodeLibrary._finalize_specific = timed(cg.JITCodeLibrary._finalize_specific, "codegen", lib)
    state_name = lambda self, state: state.func_id.func_qualname  # noqa: E731
    tp.NativeLowering.run_pass = timed(tp.NativeLowering.run_pass, "lower", state_name)
    tp.NopythonTypeInference.run_pass = timed(tp.NopythonTypeInference.run_pass, "typing", state_name)

    class Compiles(ev.Listener):
        def on_start(self, event):
            d = event.data["dispatcher"]
            sigs[d.py_func.__qualname__].add(str(event.data["args"]))
            enter(d.py_func.__qualname__, "passes")

        def on_end(self, event):
            leave()

    ev.register("numba:compile", Compiles())
    return table, sigs


def _phases(scenario: str, duration: float, top: int) -> dict:
    table, sigs = _install_phase_hooks()
    cpu0, wall0 = time.process_time(), time.perf_counter()
    from rig_emulator.api import simulate

    simulate(scenario, duration=duration)
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    rows = sorted(({"name": n, "signatures": len(sigs.get(n, ())), **{p: d.get(p, 0.0) for p in _PHASES}}
                   for n, d in table.items()), key=lambda r: -sum(r[p] for p in _PHASES))
    totals = {p: sum(r[p] for r in rows) for p in _PHASES}
    print(f"cold {scenario} {duration:g} s: CPU {cpu:.1f} s, wall {wall:.1f} s, load average {os.getloadavg()[0]:.1f}")
    print("CPU s per phase: " + ", ".join(f"{p} {v:.1f}" for p, v in totals.items()) +
          f" (numba {totals['typing'] + totals['passes'] + totals['lower']:.1f}, "
          f"LLVM {sum(totals[p] for p in _PHASES[3:]):.1f})")
    print(f"\n{'function':32s} {'sigs':>4s} " + " ".join(f"{p:>7s}" for p in _PHASES) + "   total")
    for r in rows[:top]:
        print(f"{r['name'][-32:]:32s} {r['signatures']:4d} " + " ".join(f"{r[p]:7.2f}" for p in _PHASES)
              + f" {sum(r[p] for p in _PHASES):7.2f}")
    return {"scenario": scenario, "cpu_s": cpu, "wall_s": wall, "totals": totals, "functions": rows}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.compile_profile", description=__doc__.split("\n\n")[0])
    p.add_argument("--scenario", default="hover")
    p.add_argument("--duration", type=float, default=0.1)
    p.add_argument("--top", type=int, default=25)
    p.add_argument("--json", help="also write the figures to this JSON file")
    p.add_argument("--phases", action="store_true", help="CPU time per function and phase (typing, lowering, "
                                                         "LLVM optimisation, code generation) instead")
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
        if args.phases:
            out = _phases(args.scenario, args.duration, args.top)
        else:
            out = _profile(args.scenario, args.duration)
    finally:
        if not args.cache:
            shutil.rmtree(cache, ignore_errors=True)
    if args.phases:
        if args.json:
            with open(args.json, "w") as f:
                json.dump(out, f, indent=1)
        return 0
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
