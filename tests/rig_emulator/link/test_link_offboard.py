"""Offboard set-points over a real socket (pymavlink): frames, type_mask, thrust, body rates,
refusals with a STATUSTEXT, the set-point timeout and SET_ACTUATOR_CONTROL_TARGET.

Each test streams set-points to a rig served at 8x real time and judges it by its own
telemetry (LOCAL_POSITION_NED, ATTITUDE, HEARTBEAT) as a ground station would."""

import math

import numpy as np
import pytest

from protocol.dialect import mavlink as M
from protocol.geodesy import Home, local_enu_to_global
from rig_emulator.link.commands.modes import AUTO, AUTO_LOITER, OFFBOARD, split_custom_mode
from rig_emulator.testing.rig import RigThread, command, connect, recv, recv_text, start_offboard

POS = M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE | M.POSITION_TARGET_TYPEMASK_Z_IGNORE
VEL = M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE
ACC = M.POSITION_TARGET_TYPEMASK_AX_IGNORE | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
YAW, RATE = M.POSITION_TARGET_TYPEMASK_YAW_IGNORE, M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
SPEEDUP = 8.0


@pytest.fixture
def link(request):
    airframe = getattr(request, "param", "hilms")
    with RigThread(speedup=SPEEDUP, overrides={"offboard.loss_timeout": 30.0}, airframe=airframe) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert command(conn, M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 50_000).result == 0
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        yield rig, conn
        conn.close()


def local(conn, frame, mask, x=(0, 0, 0), v=(0, 0, 0), a=(0, 0, 0), yaw=0.0, yaw_rate=0.0):
    conn.mav.set_position_target_local_ned_send(0, 1, 1, frame, mask, *x, *v, *a, yaw, yaw_rate)


def hold_for(conn, sim_s, send):
    """Stream ``send()`` at 10 Hz of simulated time for ``sim_s``; returns the last LOCAL_POSITION_NED."""
    last, t_end = None, None
    while True:
        send()
        m = recv(conn, "LOCAL_POSITION_NED", 5.0)
        assert m is not None
        t_end = m.time_boot_ms * 1e-3 + sim_s if t_end is None else t_end
        last = m
        for _ in range(4):  # LOCAL_POSITION_NED at 20 Hz: a set-point every 5th
            m = recv(conn, "LOCAL_POSITION_NED", 5.0)
            last = m or last
        if last.time_boot_ms * 1e-3 >= t_end:
            return last


def mode_of(conn):
    hb = recv(conn, "HEARTBEAT", 5.0)
    return split_custom_mode(hb.custom_mode)


def test_velocity_climb_then_body_offset_position(link):
    rig, conn = link
    climb = lambda: local(conn, M.MAV_FRAME_LOCAL_NED, POS | ACC | YAW | RATE, v=(0, 0, -0.4))  # noqa: E731
    assert start_offboard(conn, climb).result == M.MAV_RESULT_ACCEPTED
    mid = hold_for(conn, 2.0, climb)
    last = hold_for(conn, 2.0, climb)
    # climbing at 0.4 m/s: judged on the climb over 2 s (a single LOCAL_POSITION_NED.vz of the hardware
    # rig scatters by up to 0.25 m/s about it)
    rate = (mid.z - last.z) / ((last.time_boot_ms - mid.time_boot_ms) * 1e-3)
    assert -last.z > 1.0 and abs(rate - 0.4) < 0.06, (rate, last)
    assert mode_of(conn)[0] == OFFBOARD
    assert rig.server.counters.dropped.get("setpoint_refused", 0) == 0
    # one BODY_OFFSET_NED set-point: 1 m forward of where the rig is (forward = its heading), same height
    snap = rig.server.rig.snapshot()
    heading_ned = math.pi / 2 - snap.euler[2]
    here_ned = np.array([snap.position[1], snap.position[0]])
    local(conn, M.MAV_FRAME_BODY_OFFSET_NED, VEL | ACC | YAW | RATE, x=(1.0, 0.0, 0.0))
    hold_for(conn, 0.5, lambda: None)
    target = rig.server.rig.snapshot().position_target
    want_ned = here_ned + [math.cos(heading_ned), math.sin(heading_ned)]
    assert np.allclose([target[1], target[0]], want_ned, atol=0.1), (target, want_ned)
    last = hold_for(conn, 10.0, lambda: None)
    assert np.allclose([last.x, last.y], want_ned, atol=0.25), (last, want_ned)


def test_global_int_position(link):
    rig, conn = link
    home = rig.server.ctx.home
    lat, lon, _ = local_enu_to_global(home, [1.5, -1.0, 0.0])
    send = lambda: conn.mav.set_position_target_global_int_send(  # noqa: E731
        0, 1, 1, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, VEL | ACC | YAW | RATE, round(lat * 1e7), round(lon * 1e7), 1.5,
        0, 0, 0, 0, 0, 0, 0, 0)
    assert start_offboard(conn, send).result == M.MAV_RESULT_ACCEPTED
    last = hold_for(conn, 12.0, send)
    assert np.allclose([last.y, last.x, -last.z], [1.5, -1.0, 1.5], atol=0.25), last


# The ideal plant: this test checks the set-point's mapping (thrust fraction, FRD body rates), and its
# figures (hover + 0.05 climbs, 0.3 rad/s of yaw tracked in 2 s) are the ideal plant's. On `hilms` the
# fraction that hovers is higher (its thrust ceiling and efficiencies) and, from the 13 deg hang on the
# virtual ground, a 0.3 rad/s yaw-rate set-point at hover + 0.05 reached 0.12 rad/s and fell back to 0
# within 3 s (measured with LiveRig, also with the joint's friction off): the hardware rig's attitude
# set-points with thrust need their own study (hover thrust per plant), not this mapping test.
@pytest.mark.parametrize("link", ["hilms-ideal"], indirect=True)
def test_attitude_thrust_moves_altitude_and_body_rates_turn(link):
    rig, conn = link
    q_level = [math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)]  # yaw 90 deg (east): the rig's start heading
    full = lambda: conn.mav.set_attitude_target_send(0, 1, 1, 0b111, q_level, 0, 0, 0, 1.0)  # noqa: E731
    assert start_offboard(conn, full).result == M.MAV_RESULT_ACCEPTED
    last = hold_for(conn, 1.5, full)
    assert -last.z > 0.5 and -last.vz > 0.5, last  # thrust 1.0: 4 x 8.3 N against 21.9 N of weight
    zero = lambda: conn.mav.set_attitude_target_send(0, 1, 1, 0b111, q_level, 0, 0, 0, 0.0)  # noqa: E731
    last = hold_for(conn, 4.0, zero)
    assert -last.z < 0.05, last  # thrust 0: back on the virtual ground
    hover = rig.server.rig.hover_thrust_fraction()
    rates = lambda: conn.mav.set_attitude_target_send(  # noqa: E731
        0, 1, 1, M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE, [1, 0, 0, 0], 0, 0, 0.3, hover + 0.05)
    hold_for(conn, 2.0, rates)
    att = recv(conn, "ATTITUDE", 5.0)
    assert abs(att.yawspeed - 0.3) < 0.1, att  # yaw rate tracked, FRD like MAVLink's
    assert rig.server.counters.dropped.get("setpoint_refused", 0) == 0


def test_unfollowable_setpoints_are_refused_once_with_a_reason(link):
    rig, conn = link
    for _ in range(3):
        local(conn, M.MAV_FRAME_LOCAL_NED, VEL | ACC | YAW | RATE | M.POSITION_TARGET_TYPEMASK_FORCE_SET)
    got = recv_text(conn, lambda t: "SET_POSITION_TARGET_LOCAL_NED refused" in t)
    assert got is not None and "force" in got[1]
    assert recv_text(conn, lambda t: "refused: force" in t, timeout=2.0) is None  # once, not three times
    assert rig.server.counters.dropped["setpoint_refused"] == 3  # and still counted
    local(conn, M.MAV_FRAME_GLOBAL_INT, VEL | ACC | YAW | RATE)
    assert recv_text(conn, lambda t: "GLOBAL_INT is not a local set-point frame" in t) is not None
    conn.mav.set_attitude_target_send(0, 1, 1, 0b111, [1, 0, 0, 0], 0, 0, 0, 1.5)
    assert recv_text(conn, lambda t: "thrust 1.5 must be in [0, 1]" in t) is not None
    conn.mav.set_actuator_control_target_send(0, 0, 1, 1, [0.0] * 8)
    assert recv_text(conn, lambda t: t.startswith("SET_ACTUATOR_CONTROL_TARGET refused")) is not None


def test_setpoint_timeout_holds_position():
    with RigThread(speedup=SPEEDUP, overrides={"offboard.loss_timeout": 0.5}) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        climb = lambda: local(conn, M.MAV_FRAME_LOCAL_NED, POS | ACC | YAW | RATE, v=(0, 0, -0.5))  # noqa: E731
        assert start_offboard(conn, climb).result == M.MAV_RESULT_ACCEPTED  # one set-point, then silence
        got = recv_text(conn, lambda t: t.startswith("offboard set-points lost"))
        assert got is not None and got[0] == M.MAV_SEVERITY_CRITICAL and "hold" in got[1], got
        assert mode_of(conn) == (AUTO, AUTO_LOITER)
        before = rig.server.rig.snapshot().position
        recv(conn, "HEARTBEAT", 5.0)
        after = rig.server.rig.snapshot().position
        assert abs(after[2] - before[2]) < 0.2  # the climb stopped
        conn.close()
