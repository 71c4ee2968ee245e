"""Which controller plug-in a rig flies with, from its arguments or its config."""

from __future__ import annotations

import math

from rig_emulator.config.loader import RigConfig
from rig_emulator.control.controller import OUT_ATT_DES


def plugin_binding(cfg: RigConfig, cp, n_imu: int, controller=None, external_motors: bool = False):
    """The :class:`~rig_emulator.controllers.BoundPlugin` of a rig: ``controller`` (a name, class
    or instance) or else the config's ``controller.plugin``, or else the built-in strategy
    (``control.strategy``, :func:`~rig_emulator.controllers.runtime.bind_builtin`); the config's
    ``controller.params`` override its defaults, ``controller.call = "python"`` runs a compiled
    controller's kernel as Python. Raises :class:`~rig_emulator.controllers.PluginError`."""
    from rig_emulator.controllers import bind, load_controller, no_plugin_binding
    from rig_emulator.controllers.runtime import bind_builtin

    if external_motors:
        return no_plugin_binding()
    spec = controller if controller is not None else (cfg["controller.plugin"] or None)
    if spec is None:
        ctrl_div = int(round(cfg["sim.physics_rate_hz"] / cfg["sim.control_rate_hz"]))
        return bind_builtin(cp, ctrl_div, cfg["control.strategy"], n_imu)
    ctrl = load_controller(spec, cfg["controller.params"])
    return bind(ctrl, cfg["sim.physics_rate_hz"], cfg["sim.control_rate_hz"], cp, n_imu,
                python=cfg["controller.call"] == "python")


def unreported_attitude(cout) -> None:
    """No desired attitude known (external motor commands): the supervisor's attitude-error
    test has nothing to compare with (NaN never exceeds a limit)."""
    for i in range(3):
        cout[OUT_ATT_DES + i] = math.nan
