"""A plug-in on a running rig (LiveRig, what the MAVLink link drives): parameters, failure, re-arming."""

import math

import pytest

from rig_emulator.config.loader import ConfigError, load_config
from rig_emulator.controllers import PluginError
from rig_emulator.controllers.examples.hover import LevelHover
from rig_emulator.simulation.live import LiveRig


class FailsAfterHalfASecond(LevelHover):
    def reset(self):
        self.t0 = None

    def update(self, t, obs):
        self.t0 = t if self.t0 is None else self.t0
        if t - self.t0 >= 0.5:
            raise RuntimeError("lost my way")
        return super().update(t, obs)


def _rig(ctrl):
    return LiveRig(load_config(scenario="hover", overrides={"sim.seed": 1}), chunk_steps_max=1000, controller=ctrl)


def test_parameters_change_while_flying():
    rig = _rig(LevelHover)
    rig.arm()
    rig.step(100)
    rig.set_params({"controller.params": {"kp_z": 2.5}})
    assert rig.controller.params.kp_z == 2.5 and rig.controller.params.kd_z == 3.0
    with pytest.raises(PluginError, match="unknown parameter 'controller.params.nope'"):
        rig.set_params({"controller.params": {"nope": 1.0}})
    assert rig.controller.params.kp_z == 2.5 and rig.cfg["controller.params"] == {"kp_z": 2.5}
    with pytest.raises(ConfigError, match="controller.plugin: cannot change while the rig runs"):
        rig.set_params({"controller.plugin": "x:Y"})


def test_failure_disarms_reports_and_rearming_resets():
    rig = _rig(FailsAfterHalfASecond)
    rig.arm()
    sig = rig.fault_signature()
    for _ in range(6):
        rig.step(100)
    f = rig.plugin_failure
    assert f is not None and not rig.snapshot().armed
    assert "FailsAfterHalfASecond" in str(f) and "RuntimeError: lost my way" in str(f)
    assert math.isclose(f.time_s, 0.5)
    assert rig.fault_signature() != sig
    rig.step(100)  # the plant keeps running, disarmed
    assert rig.snapshot().voltage_commands == (0.0, 0.0, 0.0, 0.0)
    rig.arm()  # reset() runs again: it flies another half second
    assert rig.plugin_failure is None
    rig.step(400)
    assert rig.plugin_failure is None and rig.snapshot().armed
    rig.step(200)
    assert rig.plugin_failure is not None and abs(rig.plugin_failure.time_s - 1.2) <= 0.0025  # 1.2 - 0.7 rounds below 0.5
