"""The compiled waypoint runner's mission features: per-leg speeds and legs whose X/Y are
taken where the rig is when they start (take-off, landing in place)."""

import numpy as np

from rig_emulator.config.loader import load_config
from rig_emulator.control.controller import REF_POS, REF_SIZE
from rig_emulator.guidance.runner import GS_DURATION, GS_SIZE, GS_TARGET, WAYPOINTS, guidance_update, start_at
from rig_emulator.simulation.params import guidance_params


def _setup(speeds, free_xy):
    cfg = load_config("hilms-ideal")
    wp = [[2.0, 0.0, 1.0], [2.0, 3.0, 1.0], [0.0, 0.0, 0.0]]
    gp = guidance_params(cfg, wp, None, None, speeds, free_xy)._replace(gtype=WAYPOINTS)
    return cfg, gp, np.zeros(GS_SIZE), np.full(3, np.nan), np.zeros(REF_SIZE)


def test_leg_duration_uses_the_leg_speed_or_the_default():
    cfg, gp, gstate, reached, ref = _setup([0.0, 1.5, 0.0], [0.0, 0.0, 0.0])
    start_at(0, 0.0, np.array([0.0, 0.0, 1.0]), gp, gstate)
    assert np.isclose(gstate[GS_DURATION], 2.0 / cfg["guidance.speed"])
    start_at(1, 0.0, np.array([2.0, 0.0, 1.0]), gp, gstate)
    assert np.isclose(gstate[GS_DURATION], 3.0 / 1.5)


def test_free_xy_leg_targets_the_start_position_and_switches_there():
    cfg, gp, gstate, reached, ref = _setup([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    here = np.array([0.7, -0.4, 1.0])
    start_at(2, 5.0, here, gp, gstate)
    assert np.allclose(gstate[GS_TARGET:GS_TARGET + 3], [0.7, -0.4, 0.0])
    guidance_update(100.0, np.array([0.7, -0.4, 0.01]), gp, gstate, reached, ref)
    assert reached[2] == 100.0  # within the 8 cm radius of the resolved target
    assert np.allclose(ref[REF_POS:REF_POS + 3], [0.7, -0.4, 0.0])
