"""The public Python API for headless runs.

>>> from rig_emulator.api import simulate
>>> result = simulate("helix", strategy="smc-flc", duration=60.0, seed=1)
>>> result.mean_errors()["x_m"]          # Eq. 45, metres
"""

from __future__ import annotations

from typing import Any

from rig_emulator.config.loader import load_config
from rig_emulator.simulation.run import SimResult, Simulation


def simulate(
    scenario: str,
    strategy: str = "smc-flc",
    duration: float | None = None,
    seed: int = 0,
    airframe: str = "hilms",
    files=(),
    controller=None,
    **overrides: Any,
) -> SimResult:
    """Run a scenario preset headless and return its :class:`SimResult`.

    ``controller``: a controller plug-in flying instead of (part of) the strategy: an instance
    or class of :class:`rig_emulator.controllers.Controller`, or ``"package.module:Name"``
    (docs/how-to/your-controller.md). A plug-in that fails raises
    :class:`~rig_emulator.controllers.PluginError` naming it, the time and the problem.

    ``overrides`` are dotted parameter keys with dots written as double underscores
    (``smc__switching="boundary"``) or passed in a dict as ``overrides={"smc.switching": ...}``.
    """
    flat = dict(overrides.pop("overrides", {}) or {})
    flat.update({k.replace("__", "."): v for k, v in overrides.items()})
    flat["control.strategy"] = strategy
    flat["sim.seed"] = seed
    if duration is not None:
        flat["sim.duration"] = float(duration)
    cfg = load_config(airframe=airframe, scenario=scenario, files=files, overrides=flat)
    return Simulation(cfg, controller=controller).run()
