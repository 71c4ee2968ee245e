"""What the controller plug-in machinery costs a run without a plug-in: an A/B of two source trees.

``python -m benchmarks.plugin_overhead [--base COMMIT] [--this COMMIT] [--repeat N] [--duration S]``
exports ``--base`` (default: the commit before the plug-in machinery, 3f19de9) and ``--this``
(default ``HEAD``) with ``git archive`` into a temporary directory and runs, alternately in
fresh processes, the same probe on the two trees (``PYTHONPATH`` selects the tree; each tree
gets its own numba cache directory, empty at the start, so repetition 1 of each is a cold
compile):

* **cold compile**: wall time of the first ``simulate("helix", "smc-flc", 0.01 s)`` in a
  process whose cache is empty (import excluded) - the issue allows the plug-in machinery
  10 % more;
* **warm start**: the same in later repetitions (cache load);
* **steady state**: the real-time factor of ``simulate("helix", strategy, duration)`` for the
  four built-in strategies (median of ``--calls`` calls, default three) - the issue asks for no
  cost; and the best call over all repetitions (on a busy machine the least disturbed one).

Ratios are this tree over the base, per repetition (the two run back to back), median over
repetitions. Wall-clock figures on a loaded machine are noisy: quote them with the load.

**Which plant.** Both trees fly the same plant: ``--airframe ideal`` (the default) is the ideal
plant in each tree (``hilms-ideal`` where the tree has it, else ``hilms``, which was the ideal
plant), so an A/B across the commits that added the hardware rig does not compare the hardware
rig with the ideal one. ``--airframe hilms`` (repeatable) names an airframe both trees have.

**Which commits.** The plug-in machinery alone is ``--base 3f19de9 --this a324065``
(the plug-in machinery from its first commit to its last before it was merged); ``HEAD``
against 3f19de9 also carries everything merged since (the hardware plant, the link work). The
same A/B measures a speed change of the step loop: ``--base f83dea3 --airframe hilms
--airframe ideal --strategies smc-flc`` (the hardware rig, before and after a change).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

BASE = "3f19de9"
STRATEGIES = ("smc-flc", "flc", "smc", "pid")

_PROBE = r"""
import json, os, sys, time
t0 = time.perf_counter()
from rig_emulator.api import simulate
import rig_emulator
t1 = time.perf_counter()
presets = os.path.join(os.path.dirname(rig_emulator.__file__), "presets", "airframes")
def airframe(name):  # "ideal": the tree's ideal plant (older trees have no hilms-ideal: their hilms was ideal)
    if name != "ideal":
        return name
    return "hilms-ideal" if os.path.exists(os.path.join(presets, "hilms-ideal.toml")) else "hilms"
airframes = sys.argv[3].split(",")
if sys.argv[5] == "cpu":  # the loop's own CPU time: the run module times it with time.perf_counter
    import types
    import rig_emulator.simulation.run as run_module
    run_module.time = types.SimpleNamespace(perf_counter=time.thread_time)
simulate("helix", strategy="smc-flc", duration=0.01, seed=0, airframe=airframe(airframes[0]))
first = time.perf_counter() - t1
out = {"tree": rig_emulator.__file__, "import_s": t1 - t0, "first_call_s": first}
for a in airframes:
    for s in sys.argv[2].split(","):
        rtfs = []
        for _ in range(int(sys.argv[4])):
            r = simulate("helix", strategy=s, duration=float(sys.argv[1]), seed=0, airframe=airframe(a))
            rtfs.append(r.sim_time_s / r.wall_time_s)
        rtfs.sort()
        out[f"rtf.{a}.{s}"] = rtfs[len(rtfs) // 2]
        out[f"best.{a}.{s}"] = rtfs[-1]
print(json.dumps(out))
"""


def _export(commit: str, repo: Path, dest: Path) -> Path:
    dest.mkdir()
    tar = dest / "tree.tar"
    with open(tar, "wb") as f:
        subprocess.run(["git", "-C", str(repo), "archive", commit], stdout=f, check=True)
    tree = dest / "tree"
    tree.mkdir()
    with tarfile.open(tar) as t:
        t.extractall(tree, filter="data")
    return tree


def _run(tree: Path, cache: Path, duration: float, strategies, airframes, calls: int = 3, clock: str = "wall") -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), HILMS_NUMBA_CACHE=str(cache), NUMBA_CACHE_DIR=str(cache))
    p = subprocess.run([sys.executable, "-c", _PROBE, str(duration), ",".join(strategies), ",".join(airframes),
                        str(calls), clock],
                       env=env, cwd=tree,
                       capture_output=True, text=True, check=False)
    if p.returncode != 0:
        raise RuntimeError(f"probe on {tree} failed:\n{p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.plugin_overhead", description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", default=BASE, help="the commit to compare with (default %(default)s)")
    ap.add_argument("--this", default="HEAD", help="the commit measured (default %(default)s)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration", type=float, default=20.0, help="simulated s per steady-state call")
    ap.add_argument("--airframe", action="append", dest="airframes",
                    help="airframe both trees fly ('ideal': each tree's ideal plant; repeatable; default ideal)")
    ap.add_argument("--strategies", default=",".join(STRATEGIES), help="comma list (default %(default)s)")
    ap.add_argument("--calls", type=int, default=3,
                    help="steady-state calls per airframe and strategy in each process: their median and their "
                         "best (the least disturbed, for a busy machine) are reported (default %(default)s)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="what times the steady-state calls: 'wall' (SimResult.wall_time_s, as the benchmarks) or "
                         "'cpu' (the thread's CPU time over the same span, the run module's timer replaced in the "
                         "probe: on a shared machine the figure the other processes disturb least; default "
                         "%(default)s)")
    ap.add_argument("--also", action="append", default=[], metavar="COMMIT",
                    help="another commit measured in the same alternation and reported against --base like --this "
                         "(repeatable; e.g. a step between the two)")
    ap.add_argument("--out", help="write the raw runs as JSON")
    args = ap.parse_args(argv)
    airframes = args.airframes or ["ideal"]
    strategies = args.strategies.split(",")
    repo = Path(__file__).resolve().parent.parent
    commits = {"base": args.base, "this": args.this}
    commits.update({f"also-{c}": c for c in args.also})
    names = list(commits)
    runs = {n: [] for n in names}
    with tempfile.TemporaryDirectory(prefix="hilms-ab-") as tmp:
        tmp = Path(tmp)
        trees = {n: _export(c, repo, tmp / n) for n, c in commits.items()}
        for rep in range(args.repeat):
            for name in (names if rep % 2 == 0 else names[::-1]):
                r = _run(trees[name], tmp / f"cache-{name}", args.duration, strategies, airframes, args.calls,
                         args.clock)
                runs[name].append(r)
                print(f"rep {rep + 1} {name}: " + ", ".join(f"{k} {v:.3g}" for k, v in r.items() if k != "tree"),
                      file=sys.stderr, flush=True)
    with open("/proc/loadavg") if os.path.exists("/proc/loadavg") else open(os.devnull) as f:
        load = f.read().strip()
    for name in names[1:]:
        _report(runs[name], runs["base"], commits[name], args, airframes, strategies, load)
    if args.out:
        Path(args.out).write_text(json.dumps(runs, indent=1))
    return 0


def _report(this, base, commit, args, airframes, strategies, load) -> None:
    print(f"A/B: {commit} vs {args.base}, {args.repeat} repetitions, {args.calls} calls of {args.duration:g} s, "
          f"airframes {', '.join(airframes)}, clock {args.clock}, load average {load}")
    cold = this[0]["first_call_s"] / base[0]["first_call_s"]
    print(f"cold compile + first call: {this[0]['first_call_s']:.1f} s vs {base[0]['first_call_s']:.1f} s"
          f" (ratio {cold:.3f}; target <= 1.10)")
    if args.repeat > 1:
        warm = [t["first_call_s"] / b["first_call_s"] for t, b in zip(this[1:], base[1:])]
        print(f"warm start (cache load) ratio: median {statistics.median(warm):.3f}")
    for a in airframes:
        for s in strategies:
            key = f"rtf.{a}.{s}"
            ratios = [t[key] / b[key] for t, b in zip(this, base)]
            tm, bm = statistics.median(t[key] for t in this), statistics.median(b[key] for b in base)
            print(f"{a} {s}: real-time factor {tm:.0f}x vs {bm:.0f}x ({1e3 / tm:.3f} vs {1e3 / bm:.3f} us/step), "
                  f"ratio median {statistics.median(ratios):.3f} (min {min(ratios):.3f}, max {max(ratios):.3f})")
            best = f"best.{a}.{s}"
            if all(best in r for r in this + base):
                bt = max(t[best] for t in this)
                bb = max(b[best] for b in base)
                print(f"{a} {s}: best call of all repetitions {bt:.0f}x vs {bb:.0f}x ({1e3 / bt:.3f} vs "
                      f"{1e3 / bb:.3f} us/step), ratio {bt / bb:.3f}")


if __name__ == "__main__":
    sys.exit(main())
