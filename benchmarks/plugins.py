"""plugins: controller plug-ins in both call paths against the built-in strategy.

Probes (each in a fresh process; ``rig_emulator.api.simulate("helix", strategy="pid", ...)``
with the full sensing chain, 1 kHz physics, 500 Hz control):

* ``plugin-none`` - no plug-in: the built-in ``pid`` strategy (the reference);
* ``plugin-compiled-pid`` - the PID example (rig_emulator/controllers/examples/pid.py) as a
  compiled plug-in: its kernel is a ``cfunc`` called through a function pointer inside the
  compiled loop (target >= 300x real time);
* ``plugin-python-pid`` - the same kernel run as plain Python from the loop
  (``controller.call = "python"``);
* ``plugin-python-trivial`` - a trivial plain-Python controller (hover thrust, no torque;
  hover scenario) called at 500 Hz from the compiled loop (target >= 50x real time);
* ``plugin-python-cascaded`` - a 30-line cascaded PID written in plain Python as a user writes
  one (rig_emulator/controllers/examples/cascaded_pid.py: ``self.params.<name>``, ``obs.<name>``,
  Python floats and lists) at 500 Hz on the helix (target >= 150x real time).

Figures: the steady-state real-time factor of each (median of ``inner`` calls after the first),
each plug-in's speed as a share of the built-in's in the same repetition, and the first call
(repetition 1: cold numba cache, so compile + run; the plug-in probes then also compile their
own kernel's ``cfunc``). What the plug-in machinery costs a run *without* a plug-in and the
cold compile of the loop are measured against the commit before it by
``python -m benchmarks.plugin_overhead`` (an A/B of two source trees, see there).
"""

from __future__ import annotations

import time

from .harness import REGISTRY, Metric, ProbeStats, Target, benchmark, median, paired_ratio_metric

DURATION_S = 20.0
QUICK_S = 3.0
PROBES = {
    "plugin-none": ("helix", None, "compiled"),
    "plugin-compiled-pid": ("helix", "rig_emulator.controllers.examples.pid:PID", "compiled"),
    "plugin-python-pid": ("helix", "rig_emulator.controllers.examples.pid:PID", "python"),
    "plugin-python-trivial": ("hover", "benchmarks.plugins:TrivialHover", "python"),
    "plugin-python-cascaded": ("helix", "rig_emulator.controllers.examples.cascaded_pid:CascadedPID", "python"),
}


def _trivial_class():
    from rig_emulator.controllers import Controller

    class TrivialHover(Controller):
        """The least a Python controller can do: constant hover thrust, no torque."""

        def update(self, t, obs):
            return (obs.mass * obs.gravity, 0.0, 0.0, 0.0)

    TrivialHover.__module__ = __name__
    return TrivialHover


def __getattr__(name):  # benchmarks.plugins:TrivialHover, importable by name without importing the rig first
    if name == "TrivialHover":
        cls = _trivial_class()
        globals()["TrivialHover"] = cls
        return cls
    raise AttributeError(name)


def plugin_probe(scenario: str, controller: str | None, call: str, duration: float, inner: int) -> dict:
    from rig_emulator.api import simulate

    kw = dict(strategy="pid", duration=duration, seed=0, controller=controller,
              overrides={"controller.call": call})
    t0 = time.perf_counter()
    first = simulate(scenario, **kw)
    first_s = time.perf_counter() - t0
    rtfs = []
    for _ in range(inner):
        r = simulate(scenario, **kw)
        rtfs.append(r.sim_time_s / r.wall_time_s)
    return {"rtf": median(rtfs), "first_call_s": first_s, "mean_error.x_m": float(first.mean_errors()["x_m"])}


for _name, (_scenario, _ctrl, _call) in PROBES.items():
    REGISTRY.add_probe(
        _name, plugin_probe,
        params={"scenario": _scenario, "controller": _ctrl, "call": _call, "duration": DURATION_S, "inner": 3},
        quick={"duration": QUICK_S, "inner": 1},
        description=f"simulate({_scenario!r}, 'pid', controller={_ctrl!r}, controller.call={_call!r})",
    )

PYTHON_TARGET = (Target(">=", 50.0, "a Python plug-in"),)
COMPILED_TARGET = (Target(">=", 300.0, "a compiled plug-in"),)
CASCADED_TARGET = (Target(">=", 150.0, "plain-Python cascaded PID"),)


@benchmark("plugins", probes=tuple(PROBES), description="controller plug-ins, compiled and Python, vs the built-in")
def plugins(stats: dict[str, ProbeStats]) -> list[Metric]:
    ref = stats["plugin-none"]
    out = [ref.metric("rtf", "no plug-in (built-in pid), helix: real-time factor", "x real time")]
    comp = stats["plugin-compiled-pid"]
    out.append(comp.metric("rtf", "compiled PID plug-in, helix: real-time factor", "x real time",
                           targets=COMPILED_TARGET))
    out.append(paired_ratio_metric(comp, "rtf", ref, "rtf", "compiled plug-in speed / built-in speed"))
    py = stats["plugin-python-pid"]
    out.append(py.metric("rtf", "PID kernel as Python, helix: real-time factor", "x real time"))
    out.append(paired_ratio_metric(py, "rtf", ref, "rtf", "Python PID speed / built-in speed"))
    triv = stats["plugin-python-trivial"]
    out.append(triv.metric("rtf", "trivial Python controller at 500 Hz, hover: real-time factor", "x real time",
                           targets=PYTHON_TARGET))
    cas = stats["plugin-python-cascaded"]
    out.append(cas.metric("rtf", "30-line cascaded PID in plain Python at 500 Hz, helix: real-time factor",
                          "x real time", targets=CASCADED_TARGET))
    out.append(paired_ratio_metric(cas, "rtf", ref, "rtf", "Python cascaded PID speed / built-in speed"))
    for name in PROBES:
        s = stats[name]
        out.append(Metric(f"{name}: first call, cold numba cache", s.first("first_call_s"), "s",
                          note="compile (loop and plug-in) + one run"))
    return out
