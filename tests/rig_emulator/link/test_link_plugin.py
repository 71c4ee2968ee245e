"""A controller plug-in on a served rig, over real MAVLink (pymavlink): its failures reach the
ground station (STATUSTEXT, HEARTBEAT) and the rig keeps serving, its own parameters are MAVLink
parameters under its prefix, and it sees the offboard set-point as its reference."""

import math
import time

import numpy as np
import pytest

from protocol.dialect import mavlink as M
from rig_emulator.controllers.examples.hover import LevelHover
from rig_emulator.controllers.runtime import plugin_name
from rig_emulator.link.commands.modes import OFFBOARD, split_custom_mode
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.rig import RigThread, all_params, command, connect, recv, recv_text, start_offboard

ARM = M.MAV_CMD_COMPONENT_ARM_DISARM
POS_ONLY = (M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE
            | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE | M.POSITION_TARGET_TYPEMASK_AX_IGNORE
            | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
            | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE)


class Flaky(LevelHover):
    """LevelHover that fails ``fail_after`` s after arming in the way ``fail_mode`` says (0: never)."""

    param_prefix = "FLK_"
    params = {**LevelHover.params, "fail_after": 0.5, "fail_mode": 1.0, "w": [1.0, 1.0]}
    param_info = {"fail_mode": {"min": 0, "max": 3, "doc": "0 never, 1 raise, 2 NaN, 3 three values"},
                  "fail_after": {"min": 0.0, "max": 100.0, "unit": "s", "doc": "time after arming of the failure"}}

    def reset(self):
        self.t0 = None

    def update(self, t, obs):
        self.t0 = t if self.t0 is None else self.t0
        self.seen = (self.params.kp_z, tuple(self.params.w), tuple(obs.reference.position), obs.attitude_mode,
                     tuple(obs.reference.attitude), obs.reference.thrust, obs.reference.body_rates)
        mode = int(self.params.fail_mode)
        if mode and t - self.t0 >= self.params.fail_after:
            if mode == 1:
                raise RuntimeError("lost my way")
            if mode == 2:
                return (math.nan, 1.0, 1.0, 1.0)
            return (1.0, 1.0, 1.0)
        return super().update(t, obs)


@pytest.fixture
def link(tmp_path):
    ctrl = Flaky()
    with RigThread(speedup=8.0, controller=ctrl, state_dir=tmp_path / "state",
                   overrides={"offboard.loss_timeout": 30.0}) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        yield rig, conn, ctrl
        conn.close()


def param_set(conn, name, value):
    conn.mav.param_set_send(1, 1, name.encode(), value, M.MAV_PARAM_TYPE_REAL32)
    return recv(conn, "PARAM_VALUE", 10.0, lambda m: m.param_id == name)


def arm_once_still(rig, conn, within_s: float = 30.0) -> None:
    """Arm; while the pre-arm check refuses it (the hardware rig, its motors stopped in flight,
    swings on its joint until it hangs still) wait a little rig time and ask again."""
    t_end = rig.server.rig.time_s + within_s
    while True:
        ack = command(conn, ARM, 1)
        if ack.result == M.MAV_RESULT_ACCEPTED:
            return
        assert ack.result == M.MAV_RESULT_DENIED and rig.server.rig.time_s < t_end, (ack, rig.server.rig.time_s)
        t_next = rig.server.rig.time_s + 0.5
        while rig.server.rig.time_s < t_next:
            assert recv(conn, "ATTITUDE", 5.0) is not None


def test_failures_reach_the_ground_station_and_rearming_after_a_fix_flies(link):
    rig, conn, ctrl = link
    problems = {1: "RuntimeError: lost my way (", 2: "returned a non-finite command [nan, 1, 1, 1]",
                3: "update() must return 4 numbers (motor thrusts 1-4 (N)), got 3"}
    for mode, problem in problems.items():
        assert param_set(conn, "FLK_FAIL_MODE", mode).param_value == mode
        arm_once_still(rig, conn)
        got = recv_text(conn, lambda t: "test_link_plugin:Flaky at t = " in t, timeout=30.0)
        assert got is not None, f"no STATUSTEXT for fail_mode {mode}"
        severity, text = got
        assert severity == M.MAV_SEVERITY_CRITICAL and problem in text and "motors stopped, disarmed" in text, text
        t_fail = float(text.split("at t = ")[1].split(" s")[0])
        assert t_fail > 0.0
        assert rig.server.rig.plugin_failure is not None and not rig.server.rig.armed
        hb = recv(conn, "HEARTBEAT", 5.0, lambda m: m.system_status == M.MAV_STATE_EMERGENCY)
        assert hb is not None and not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED
        # the link keeps serving: a parameter read and a command are answered
        conn.mav.param_request_read_send(1, 1, b"FLK_KP_Z", -1)
        assert recv(conn, "PARAM_VALUE", 10.0, lambda m: m.param_id == "FLK_KP_Z") is not None
    # the fix: never fail; arming again runs reset() and the plug-in flies on
    assert param_set(conn, "FLK_FAIL_MODE", 0).param_value == 0
    arm_once_still(rig, conn)
    assert recv_text(conn, lambda t: t.endswith("test_link_plugin:Flaky: armed again, reset()")) is not None
    t_arm = rig.server.rig.time_s
    assert recv(conn, "HEARTBEAT", 10.0, lambda m: m.system_status == M.MAV_STATE_ACTIVE) is not None
    while rig.server.rig.time_s < t_arm + 2.0:
        assert recv(conn, "ATTITUDE", 5.0) is not None
    assert rig.server.rig.armed and rig.server.rig.plugin_failure is None


def test_plugin_parameters_are_mavlink_parameters(link, tmp_path):
    rig, conn, ctrl = link
    n_rig = len(ParamTable())
    got = all_params(conn, timeout=30.0)
    names = {m.param_id: m for m in got.values()}
    assert len(got) == n_rig + 8 and all(m.param_count == n_rig + 8 for m in got.values())
    assert names["FLK_KP_Z"].param_value == 4.0 and names["FLK_KP_Z"].param_index >= n_rig
    assert names["FLK_W1"].param_value == 1.0 and "FLK_W2" in names and "FLK_W3" not in names
    assert param_set(conn, "FLK_KP_Z", 2.5).param_value == 2.5
    assert param_set(conn, "FLK_W2", 0.25).param_value == 0.25
    assert ctrl.params.kp_z == 2.5 and list(ctrl.params.w) == [1.0, 0.25] and ctrl.params.kd_z == 3.0
    # refused: out of the plug-in's declared range, not finite; the value is unchanged and said why
    for name, bad, old in (("FLK_FAIL_MODE", 7.0, 1.0), ("FLK_KP_Z", math.inf, 2.5)):
        conn.mav.param_set_send(1, 1, name.encode(), bad, M.MAV_PARAM_TYPE_REAL32)
        echo = recv(conn, "PARAM_VALUE", 10.0, lambda m, n=name: m.param_id == n)
        assert echo is not None and echo.param_value == old
        why = recv_text(conn, lambda t, n=name: t.startswith(f"{n} rejected"))
        assert why is not None and why[0] == M.MAV_SEVERITY_ERROR, why
    # the running controller sees the values
    conn.mav.param_set_send(1, 1, b"FLK_FAIL_MODE", 0.0, M.MAV_PARAM_TYPE_REAL32)
    assert command(conn, ARM, 1).result == M.MAV_RESULT_ACCEPTED
    t0 = rig.server.rig.time_s
    while rig.server.rig.time_s < t0 + 0.2:
        assert recv(conn, "ATTITUDE", 5.0) is not None
    assert ctrl.seen[:2] == (2.5, (1.0, 0.25))
    # stored under the plug-in's name: a new rig with the same plug-in starts with them
    stored = rig.state.params.plugins[plugin_name(Flaky)]
    assert stored == {"FLK_KP_Z": 2.5, "FLK_W2": 0.25, "FLK_FAIL_MODE": 0.0}


def test_a_restarted_rig_restores_the_plugin_parameters(tmp_path):
    from rig_emulator.link.parameters.store import ParamStore
    from rig_emulator.link.state.directory import StateDir

    d = StateDir(tmp_path)
    ParamStore(d).save("FLK_KP_Z", 2.5, plugin=plugin_name(Flaky))
    ParamStore(d).save("SMC_K_PHI", 2.0)
    d.close()
    ctrl = Flaky()
    with RigThread(speedup=8.0, controller=ctrl, state_dir=tmp_path) as rig:
        assert ctrl.params.kp_z == 2.5 and rig.server.rig.cfg["smc.k"][0] == 2.0


def test_the_offboard_set_point_is_the_plugins_reference(link):
    rig, conn, ctrl = link
    conn.mav.param_set_send(1, 1, b"FLK_FAIL_MODE", 0.0, M.MAV_PARAM_TYPE_REAL32)
    assert command(conn, ARM, 1).result == M.MAV_RESULT_ACCEPTED
    target_ned = (0.3, -0.2, -1.5)  # north, east, down (m)
    t_end = None
    send = lambda: conn.mav.set_position_target_local_ned_send(  # noqa: E731
        0, 1, 1, M.MAV_FRAME_LOCAL_NED, POS_ONLY, *target_ned, 0, 0, 0, 0, 0, 0, 0.0, 0.0)
    assert start_offboard(conn, send).result == M.MAV_RESULT_ACCEPTED
    while t_end is None or rig.server.rig.time_s < t_end:
        send()
        m = recv(conn, "LOCAL_POSITION_NED", 5.0)
        assert m is not None
        if t_end is None:
            t_end = rig.server.rig.time_s + 1.0
    hb = recv(conn, "HEARTBEAT", 5.0)
    assert split_custom_mode(hb.custom_mode)[0] == OFFBOARD
    ref = ctrl.seen[2]  # world ENU: east, north, up
    assert ref == pytest.approx((-0.2, 0.3, 1.5), abs=1e-6), ref


def test_an_offboard_attitude_set_point_with_thrust_is_the_plugins_reference(link):
    rig, conn, ctrl = link
    conn.mav.param_set_send(1, 1, b"FLK_FAIL_MODE", 0.0, M.MAV_PARAM_TYPE_REAL32)
    assert command(conn, ARM, 1).result == M.MAV_RESULT_ACCEPTED
    roll = math.radians(5.0)  # about the front axis, level pitch, heading north
    q = (math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0)
    t_end = None
    send = lambda: conn.mav.set_attitude_target_send(  # noqa: E731
        0, 1, 1, M.ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE | M.ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE
        | M.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE, q, 0, 0, 0, 0.6)
    assert start_offboard(conn, send).result == M.MAV_RESULT_ACCEPTED
    while t_end is None or rig.server.rig.time_s < t_end:
        send()
        assert recv(conn, "ATTITUDE", 5.0) is not None
        if t_end is None:
            t_end = rig.server.rig.time_s + 0.5
    _, _, _, attitude_mode, attitude, thrust, body_rates = ctrl.seen
    assert attitude_mode and not body_rates
    assert thrust == pytest.approx(rig.server.rig.collective_thrust_from_fraction(float(np.float32(0.6))), rel=1e-12) and thrust > 10.0
    assert abs(abs(attitude[0]) - roll) < 1e-6, attitude  # the paper's phi; its sign is the rig's convention


def test_rig_emulator_serve_prints_the_failure_and_keeps_serving():
    """The real command: ``rig-emulator serve --controller ...``; the console has the reason too."""
    from rig_emulator.testing.rig import RigProcess

    name = "tests.rig_emulator.link.test_link_plugin:Flaky"
    with RigProcess(speedup=4.0, args=["--controller", name, "--set", "controller.params={fail_after=0.2}"]) as rig:
        conn = connect(rig.tcp_url)
        assert command(conn, ARM, 1).result == M.MAV_RESULT_ACCEPTED
        got = recv_text(conn, lambda t: t.startswith(f"controller {name} at t = "), timeout=30.0)
        assert got is not None and "RuntimeError: lost my way" in got[1]
        assert command(conn, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION).result == 0
        conn.close()
        deadline = time.monotonic() + 10.0
        while not any("CRITICAL: controller " + name in line for line in rig.output) and time.monotonic() < deadline:
            time.sleep(0.05)
    assert any("CRITICAL: controller " + name in line and "lost my way" in line for line in rig.output), rig.output


def test_parameters_act_on_the_plugin_after_a_reboot():
    """A plug-in loaded by name is built anew by a REBOOT (with its parameters); PARAM_SET acts on the new one."""
    name = "rig_emulator.controllers.examples.hover:LevelHover"
    with RigThread(speedup=8.0, overrides={"controller.plugin": name}) as rig:
        conn = connect(rig.tcp_url)
        assert param_set(conn, "HOV_KP_Z", 2.5).param_value == 2.5
        before = rig.server.rig.controller
        assert command(conn, M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 1).result == M.MAV_RESULT_ACCEPTED
        after = rig.server.rig.controller
        assert after is not before and after.params.kp_z == 2.5
        assert param_set(conn, "HOV_KD_Z", 1.5).param_value == 1.5
        assert after.params.kd_z == 1.5 and after.params.kp_z == 2.5
        conn.mav.param_request_read_send(1, 1, b"HOV_KP_Z", -1)
        assert recv(conn, "PARAM_VALUE", 10.0, lambda m: m.param_id == "HOV_KP_Z").param_value == 2.5
        conn.close()
