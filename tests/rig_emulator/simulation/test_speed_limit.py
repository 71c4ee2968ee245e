"""guidance.max_speed (PX4's MPC_XY_VEL_MAX) caps every leg speed: the cruise speed
(MPC_XY_CRUISE), per-leg mission / DO_REPOSITION speeds and DO_CHANGE_SPEED."""

import numpy as np

from rig_emulator.config.loader import load_config
from rig_emulator.simulation.live import LiveRig
from rig_emulator.simulation.params import guidance_params


def test_leg_speeds_are_capped_at_max_speed():
    cfg = load_config(overrides={"guidance.speed": 1.5, "guidance.max_speed": 1.0})
    gp = guidance_params(cfg, [[0, 0, 1], [1, 0, 1], [2, 0, 1]], speeds=[0.0, 0.4, 3.0])
    assert gp.speed == 1.0
    assert list(gp.speeds) == [0.0, 0.4, 1.0]  # 0: the (capped) cruise speed
    rig = LiveRig(load_config(overrides={"guidance.max_speed": 1.0}))
    rig.fly_path([[1.0, 0.0, 1.0]], speeds=[2.0])
    assert rig.sim.gp.speeds[0] == 1.0 and rig.sim.gp.speed == 0.5
    rig.change_speed(4.0)  # DO_CHANGE_SPEED above the limit: flown at the limit
    assert rig.sim.gp.speed == 1.0
    rig.change_speed(0.8)
    assert rig.sim.gp.speed == 0.8
    rig.set_param("guidance.max_speed", 0.6)  # a lower limit applies to the legs being flown
    assert rig.sim.gp.speed == 0.6 and np.all(rig.sim.gp.speeds <= 0.6)
