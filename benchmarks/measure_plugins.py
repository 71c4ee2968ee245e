"""The plug-ins' figures in one process, on the warm numba cache of this checkout.

    python -m benchmarks.measure_plugins speed [--duration 20]     # real-time factors, wall and CPU
    python -m benchmarks.measure_plugins pid-equivalence           # PID plug-in vs built-in, 60 s helix

``speed``: per case, one warm-up run then three timed runs of ``--duration`` simulated
seconds (1 kHz physics, 500 Hz control, full sensing chain): the real-time factor by wall
clock and by the CPU time of the stepping thread (the machine's other load inflates the
latter far less; both are printed with the load average). Cases: the built-in ``pid``
strategy (helix), the PID example compiled and as Python (helix), a trivial plain-Python
controller and a trivial compiled one (hover thrust, no torque; hover). Targets:
>= 50x for the trivial Python controller, >= 300x for a compiled one.

``pid-equivalence``: the 60 s helix, seed 0, built-in ``pid`` against
rig_emulator.controllers.examples.pid:PID in both call paths: the largest difference over
every logged column (the columns a plug-in does not report, sliding surfaces and Eq. 34's
virtual inputs, are NaN for it and skipped). Target 1e-9.

Not a benchmark (``python -m benchmarks --only plugins`` is, with fresh processes and cold
caches); a quick check on a machine as it is.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numba
import numpy as np

from rig_emulator.config.loader import load_config
from rig_emulator.control import plugin_layout as L
from rig_emulator.controllers import CompiledController, Controller
from rig_emulator.simulation.run import Simulation

PID = "rig_emulator.controllers.examples.pid:PID"


class TrivialPython(Controller):
    def update(self, t, obs):
        return (obs.mass * obs.gravity, 0.0, 0.0, 0.0)


@numba.njit(cache=True)
def _trivial_kernel(t, obs, p, s, out):
    out[L.C_CMD] = obs[L.O_MASS] * obs[L.O_G]
    out[L.C_CMD + 1] = 0.0
    out[L.C_CMD + 2] = 0.0
    out[L.C_CMD + 3] = 0.0
    return 0


class TrivialCompiled(CompiledController):
    kernel = _trivial_kernel


CASES = [
    ("built-in pid strategy, helix", "helix", None, "compiled"),
    ("PID example compiled, helix", "helix", PID, "compiled"),
    ("PID example as Python, helix", "helix", PID, "python"),
    ("trivial Python controller, hover", "hover", TrivialPython, "python"),
    ("trivial compiled controller, hover", "hover", TrivialCompiled, "compiled"),
]


def speed(duration: float) -> None:
    print(f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} CPUs)")
    for label, scenario, ctrl, call in CASES:
        ov = {"control.strategy": "pid", "sim.duration": duration, "controller.call": call}
        if isinstance(ctrl, str):
            ov["controller.plugin"] = ctrl
        cfg = load_config(scenario=scenario, overrides=ov)
        walls, cpus = [], []
        for i in range(4):
            sim = Simulation(cfg, controller=None if isinstance(ctrl, str) else ctrl)
            sim.warm_up()
            n = int(round(duration / sim.dt))
            w0, c0 = time.perf_counter(), time.thread_time()
            sim.advance(n)
            w, c = time.perf_counter() - w0, time.thread_time() - c0
            if sim.plugin_failure is not None:
                raise sim.plugin_failure
            if i:
                walls.append(duration / w)
                cpus.append(duration / c)
        print(f"{label} ({cfg['sim.control_rate_hz']:g} Hz control, {cfg['sim.physics_rate_hz']:g} Hz physics): "
              f"{statistics.median(walls):.0f}x real time by the wall clock "
              f"({', '.join(f'{x:.0f}' for x in walls)}), {statistics.median(cpus):.0f}x by CPU time "
              f"({', '.join(f'{x:.0f}' for x in cpus)})", flush=True)
    print(f"load average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


def pid_equivalence() -> None:
    base = {"control.strategy": "pid", "sim.seed": 0}
    ref = Simulation(load_config(scenario="helix", overrides=base)).run()
    for call in ("compiled", "python"):
        run = Simulation(load_config(scenario="helix", overrides={**base, "controller.plugin": PID,
                                                                   "controller.call": call})).run()
        a, b = ref.log, run.log
        unreported = np.isnan(b).all(axis=0) & ~np.isnan(a).all(axis=0)
        keep = ~unreported
        same_nan = np.array_equal(np.isnan(a[:, keep]), np.isnan(b[:, keep]))
        diff = np.nanmax(np.abs(a[:, keep] - b[:, keep]))
        print(f"{call}: {run.sim_time_s:g} s helix, {int(keep.sum())} of {a.shape[1]} logged columns compared "
              f"(not reported by a plug-in: {np.where(unreported)[0].tolist()}): max |plug-in - built-in| = {diff:.3g}, "
              f"NaN where the built-in has NaN: {same_nan}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    s = sub.add_parser("speed")
    s.add_argument("--duration", type=float, default=20.0)
    sub.add_parser("pid-equivalence")
    args = p.parse_args()
    if args.what == "speed":
        speed(args.duration)
    else:
        pid_equivalence()


if __name__ == "__main__":
    main()
