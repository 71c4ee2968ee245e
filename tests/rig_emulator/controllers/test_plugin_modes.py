"""What a plug-in replaces, what it commands, its rate, what it sees, its parameters, and the
rig run with motor commands from outside (lockstep)."""

import math

import numpy as np
import pytest

from rig_emulator.api import simulate
from rig_emulator.config.loader import load_config
from rig_emulator.control import plugin_layout as L
from rig_emulator.controllers import Controller, PluginError
from rig_emulator.controllers.examples import pid as pid_example
from rig_emulator.controllers.examples.hover import LevelHover
from rig_emulator.controllers.examples.lqr import LQRAttitude
from rig_emulator.physics.motors import voltage_for_thrust
from rig_emulator.simulation.run import Simulation


class PositionPID(Controller):
    """The built-in PID position loop alone (Eq. 33, 35), in plain Python; the rig's attitude loop
    (and reference filter) does the rest: flies exactly like strategy 'pid'."""

    replaces = "position"
    commands = "attitude"

    def reset(self):
        self.integ = np.zeros(3)

    def update(self, t, obs):
        p = pid_example.PID.params
        ref = obs.reference
        a = [0.0, 0.0, 0.0]
        for i in range(3):
            a[i] = pid_example._pid.py_func(ref.position[i] - obs.position[i], ref.velocity[i] - obs.velocity[i],
                                            ref.acceleration[i], _flat(p), pid_example.POS_KP, self.integ, i, obs.dt)
        phi, theta, _ = obs.euler
        c = max(math.cos(theta) * math.cos(phi), math.cos(obs.max_tilt))
        u1 = max(obs.mass * (obs.gravity + a[2]) / c, 0.0)
        ux, uy = obs.mass * a[0] / u1, obs.mass * a[1] / u1
        h = math.sqrt(ux * ux + uy * uy)
        if h > math.sin(obs.max_tilt):
            ux, uy = ux * (math.sin(obs.max_tilt) / h), uy * (math.sin(obs.max_tilt) / h)
        psi_d = ref.yaw
        phi_d = math.asin(ux * math.sin(psi_d) - uy * math.cos(psi_d))
        theta_d = math.asin((ux * math.cos(psi_d) + uy * math.sin(psi_d)) / math.cos(phi_d))
        return (u1, phi_d, theta_d, psi_d)


def _flat(p):
    return np.concatenate([np.ravel(v) for v in p.values()])


def test_position_only_plugin_feeds_the_rigs_attitude_loop():
    kw = dict(strategy="pid", duration=5.0, seed=2)
    ref = simulate("helix", **kw)
    run = simulate("helix", controller=PositionPID, **kw)
    for name in ("pos_true", "euler_true", "v_cmd", "euler_des"):
        assert np.nanmax(np.abs(ref.series[name] - run.series[name])) <= 1e-9, name


def test_position_only_plugin_may_run_slower_but_not_oddly():
    class Slow(PositionPID):
        rate_hz = 100.0

    r = simulate("helix", strategy="pid", duration=5.0, seed=2, controller=Slow)
    assert r.mean_errors()["z_m"] < 0.2

    class Odd(PositionPID):
        rate_hz = 1000.0  # faster than the rig's 500 Hz attitude loop it feeds

    with pytest.raises(PluginError, match="runs at the rig's control rate"):
        simulate("helix", duration=1.0, controller=Odd)


def test_lqr_attitude_behind_the_fuzzy_position_loop():
    me = simulate("helix", duration=20.0, seed=1, controller=LQRAttitude).mean_errors()
    assert me["x_m"] < 0.2 and me["y_m"] < 0.2 and me["z_m"] < 0.5
    assert me["phi_deg"] < 3.0 and me["theta_deg"] < 3.0


def test_motor_thrust_plugin_holds_hover():
    r = simulate("hover", duration=6.0, seed=1, controller=LevelHover, airframe="hilms-ideal")  # Eq. 40 as the plug-in assumes
    assert np.degrees(np.abs(r.series["euler_true"][-100:, :2])).max() < 2.0
    assert abs(r.series["pos_true"][-1, 2] - r.config["guidance.hover_position"][2]) < 0.1


class Spy(Controller):
    """Records what it sees; asks for raw samples."""

    raw_sensors = True
    seen: list = []

    def reset(self):
        Spy.seen.append("reset")

    def update(self, t, obs):
        Spy.seen.append((t, obs.dt, obs.reset, obs.has_truth, obs.true_position.copy(), obs.imu_raw.copy(),
                         obs.thrusts.copy(), obs.mass))
        return (obs.mass * obs.gravity, 0.0, 0.0, 0.0)


def test_what_a_plugin_sees_and_when():
    Spy.seen = []
    simulate("hover", duration=0.01, controller=Spy, sensors__calibration="none")
    assert Spy.seen[0] == "reset"
    calls = Spy.seen[1:]
    assert [c[0] for c in calls] == pytest.approx([0.002 * i for i in range(5)])  # 500 Hz, k dt
    assert all(c[1] == pytest.approx(0.002) for c in calls)
    assert calls[0][2] and not any(c[2] for c in calls[1:])
    assert not calls[0][3] and np.all(np.isnan(calls[0][4]))  # no truth on estimated feedback
    assert np.all(np.isfinite(calls[-1][5])) and calls[-1][5].shape == (5, 9)  # raw IMU counts
    assert calls[-1][7] == 2.23
    Spy.seen = []
    simulate("hover", duration=0.004, controller=Spy, sensors__feedback="ideal", sensors__calibration="none")
    assert Spy.seen[1][3] and np.all(np.isfinite(Spy.seen[1][4]))


def test_params_from_the_config():
    r = simulate("hover", duration=0.01, controller="rig_emulator.controllers.examples.hover:LevelHover",
                 overrides={"controller.params": {"kp_z": 1.5}}, sensors__calibration="none")
    assert r.steps == 10
    with pytest.raises(PluginError, match="unknown parameter 'controller.params.kp_q' \\(did you mean 'controller.params.kp_z'\\?\\)"):
        simulate("hover", duration=0.01, controller=LevelHover, overrides={"controller.params": {"kp_q": 1.0}})
    with pytest.raises(PluginError, match=r"controller.params.att_kp = 1.0: must be 3 finite numbers \(got 1 value"):
        simulate("hover", duration=0.01, controller=pid_example.PID, overrides={"controller.params": {"att_kp": 1.0}})


def test_external_motor_commands():
    cfg = load_config(scenario="hover", overrides={"sim.duration": 1.0, "sensors.calibration": "none"})
    sim = Simulation(cfg, external_motors=True)
    sim.armed = True
    hover = sim.pp.mass * sim.pp.g / 4.0
    sim.set_motor_thrusts([hover] * 4)
    sim.advance(200)
    assert np.allclose(sim.x[13:17], voltage_for_thrust(hover, sim.pp.k_v, sim.pp.v_max), rtol=1e-3)
    sim.set_motor_voltages([20.0, 1.0, 1.0, 1.0])
    assert sim.v_cmd[0] == sim.pp.v_max
    sim.armed = False
    sim.advance(10)
    assert np.all(sim.v_cmd == 0.0)
    with pytest.raises(ValueError, match="4 finite"):
        sim.set_motor_voltages([1.0, 2.0])
    with pytest.raises(ValueError, match="external_motors=True"):
        Simulation(cfg).set_motor_voltages([1.0] * 4)
