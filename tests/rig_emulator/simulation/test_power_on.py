"""A served rig at power-on (LiveRig): the hardware rig hangs still at its rest attitude, armable;
the ideal plant keeps the headless initial state; a reboot returns there with its plug-in."""

import math

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.physics.hardware import cog_gravity_torque, rest_attitude
from rig_emulator.physics.rotation import euler_from_quat, quat_from_euler, quat_to_rot
from rig_emulator.simulation.live import LiveRig
from rig_emulator.simulation.params import physics_params
from rig_emulator.simulation.prearm import prearm_failure


def _rotation(phi, theta, psi):
    q, R = np.zeros(4), np.zeros((3, 3))
    quat_from_euler(phi, theta, psi, q)
    quat_to_rot(*q, R)
    return R


def _true_euler(snap):
    return np.array(euler_from_quat(*snap.true_quaternion))


def test_rest_attitude_zeroes_the_gravity_torque_and_is_the_hanging_one():
    cfg = load_config("hilms").with_overrides({"joint.cog_offset": [0.01, 0.0, 0.02]})
    pp = physics_params(cfg)
    phi, theta = rest_attitude(pp.hw, pp.g, 0.4)
    assert np.allclose(cog_gravity_torque(_rotation(phi, theta, 0.4), pp.hw, pp.g), 0.0, atol=1e-9)
    # a 10 mm lateral offset over 20 mm below the joint: the rig tips by atan(10 / 20) = 26.6 deg
    assert math.degrees(math.hypot(phi, theta)) == pytest.approx(math.degrees(math.atan2(0.01, 0.02)), abs=0.05)
    above = physics_params(cfg.with_overrides({"joint.cog_offset": [0.01, 0.0, -0.02]}))
    assert rest_attitude(above.hw, above.g) is None  # CoG above the joint: no hanging rest
    ideal = physics_params(load_config("hilms-ideal"))
    assert rest_attitude(ideal.hw, ideal.g) is None


def test_the_hardware_rig_hangs_still_at_power_on_and_can_be_armed():
    rig = LiveRig(load_config("hilms"))
    rest = rest_attitude(rig.sim.pp.hw, rig.sim.pp.g)
    rig.step(int(round(2.0 / rig.dt)))
    snap = rig.snapshot()
    assert math.degrees(np.linalg.norm(snap.body_rates)) < 1.0  # still: no swing, no prop-wash torque
    assert np.degrees(snap.euler[:2]) == pytest.approx(np.degrees(rest), abs=0.5)
    assert prearm_failure(snap, rig.cfg) is None
    rig.reboot()
    assert rig.time_s == 0.0 and not rig.armed
    assert np.degrees(_true_euler(rig.snapshot())[:2]) == pytest.approx(np.degrees(rest), abs=1e-6)


def test_the_ideal_rig_keeps_the_headless_initial_state():
    rig = LiveRig(load_config("hilms-ideal"))
    assert np.allclose(_true_euler(rig.snapshot()), 0.0)
    assert np.all(rig.sim.x[13:17] > 0.0)  # motors at the hover voltage, as the headless scenarios start


def test_reboot_keeps_the_controller_plug_in():
    rig = LiveRig(load_config("hilms-ideal"), controller="rig_emulator.controllers.examples.pid:PID")
    before = type(rig.controller)
    rig.reboot()
    assert type(rig.controller) is before and rig.controller is not None
