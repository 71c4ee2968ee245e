"""PX4 identity, modes, standard flight commands, pre-arm checks, recovery, reboot, standard
modes and GCS loss, with pymavlink over a real socket (the rig in a thread, 8x real time)."""

import math
import time

import pytest
from pymavlink import mavutil

from protocol.dialect import mavlink as M
from protocol.geodesy import local_enu_to_global
from protocol.mission_items import MissionItem
from rig_emulator.link.commands import modes as MD
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, recv_text

ACCEPTED, DENIED, UNSUPPORTED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED, M.MAV_RESULT_UNSUPPORTED
NAN = math.nan
ENU = M.MAV_FRAME_LOCAL_ENU


@pytest.fixture
def rig():
    with RigThread(speedup=8.0) as r:
        yield r


@pytest.fixture
def gcs(rig):
    conn = connect(rig.tcp_url)
    conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    yield conn
    conn.close()


def _mode_of(conn, timeout=10.0, condition=None):
    hb = recv(conn, "HEARTBEAT", timeout, lambda m: m.get_srcSystem() == 1 and (condition is None or condition(m)))
    return None if hb is None else MD.split_custom_mode(hb.custom_mode)


def _wait_mode(conn, main, sub, timeout=30.0):
    return _mode_of(conn, timeout, lambda m: MD.split_custom_mode(m.custom_mode) == (main, sub)) == (main, sub)


def _set_mode(conn, name):
    base, main, sub = mavutil.px4_map[name]
    return command(conn, M.MAV_CMD_DO_SET_MODE, base, main, sub)


def _position(conn):
    m = recv(conn, "LOCAL_POSITION_NED", 5.0)
    return (m.y, m.x, -m.z)  # ENU


def _until(conn, predicate, timeout=60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
    return False


def _armed(conn, timeout=10.0):
    hb = recv(conn, "HEARTBEAT", timeout, lambda m: m.get_srcSystem() == 1)
    return bool(hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)


def _take_off(gcs, rig, alt=1.5, wait_loiter=True):
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    ack = command(gcs, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, NAN, NAN, NAN, rig.server.ctx.home.alt_m + alt)
    assert ack.result == ACCEPTED
    assert recv_text(gcs, lambda t: "takeoff complete" in t, timeout=60) is not None
    if wait_loiter:
        assert _wait_mode(gcs, MD.AUTO, MD.AUTO_LOITER)


def test_heartbeat_is_px4_and_every_px4_mode_name_acts_or_is_refused_with_a_reason(rig, gcs):
    hb = recv(gcs, "HEARTBEAT", 10, lambda m: m.get_srcSystem() == 1)
    assert hb.autopilot == M.MAV_AUTOPILOT_PX4
    assert mavutil.interpret_px4_mode(hb.base_mode, hb.custom_mode) == "POSCTL"
    flown = {"POSCTL", "STABILIZED", "LOITER", "RTL", "LAND", "TAKEOFF"}
    refused = {"MANUAL": "stick input", "ACRO": "stick input", "RATTITUDE": "stick input", "ALTCTL": "stick input",
               "OFFBOARD": "no offboard signal",  # PX4: only with a set-point stream flowing
               "RTGS": "ground station's position", "FOLLOWME": "FOLLOW_TARGET", "MISSION": "no mission"}
    assert set(mavutil.px4_map) == flown | set(refused)  # every name pymavlink and MAVProxy list
    for name in mavutil.px4_map:
        ack = _set_mode(gcs, name)
        if name in flown:
            assert ack.result == ACCEPTED, name
            mode = _mode_of(gcs)
            assert mavutil.interpret_px4_mode(0, MD.custom_mode(*mode)) == name
        else:
            assert ack.result == DENIED, name
            assert recv_text(gcs, lambda t, w=refused[name]: w in t) is not None, name
    assert command(gcs, M.MAV_CMD_DO_SET_MODE, 1, 9, 0).result == DENIED  # not a PX4 mode
    assert recv_text(gcs, lambda t: "not a PX4 mode" in t) is not None


def test_takeoff_is_amsl_below_minimum_uses_mis_takeoff_alt_then_land_disarms(rig, gcs):
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    ack = command(gcs, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, NAN, NAN, NAN, 5.0)  # 5 m AMSL: below home
    assert ack.result == ACCEPTED
    assert recv_text(gcs, lambda t: "Using minimum takeoff altitude" in t) is not None
    assert recv_text(gcs, lambda t: "takeoff complete" in t, timeout=60) is not None
    assert abs(_position(gcs)[2] - rig.server.rig.cfg["guidance.takeoff_altitude"]) < 0.2
    assert command(gcs, M.MAV_CMD_NAV_LAND, 0, 0, 0, NAN, NAN, NAN, NAN).result == ACCEPTED
    state = recv(gcs, "EXTENDED_SYS_STATE", 10, lambda m: m.landed_state == M.MAV_LANDED_STATE_LANDING)
    assert state is not None
    assert recv_text(gcs, lambda t: "landed" in t, timeout=60) is not None
    assert not _armed(gcs)
    assert _wait_mode(gcs, MD.AUTO, MD.AUTO_LOITER)
    assert recv(gcs, "EXTENDED_SYS_STATE", 10, lambda m: m.landed_state == M.MAV_LANDED_STATE_ON_GROUND)


def test_reposition_set_home_and_return_land_there(rig, gcs):
    _take_off(gcs, rig)
    home = rig.server.ctx.home
    lat, lon, _ = local_enu_to_global(home, [2.0, 1.0, 0.0])
    gcs.mav.command_int_send(1, 1, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_CMD_DO_REPOSITION, 0, 0, -1,
                             M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0, NAN, int(lat * 1e7), int(lon * 1e7), 2.0)
    assert recv(gcs, "COMMAND_ACK", 10, lambda m: m.command == M.MAV_CMD_DO_REPOSITION).result == ACCEPTED
    assert recv_text(gcs, lambda t: "arrived" in t, timeout=60) is not None
    e, n, u = _position(gcs)
    assert math.hypot(e - 2.0, n - 1.0) < 0.2 and abs(u - 2.0) < 0.2
    assert command(gcs, M.MAV_CMD_DO_SET_HOME, 1).result == ACCEPTED
    hp = recv(gcs, "HOME_POSITION", 10)
    assert math.hypot(hp.y - 2.0, hp.x - 1.0) < 0.2 and hp.z == 0.0
    assert command(gcs, M.MAV_CMD_DO_REPOSITION, -1, 1, 0, NAN, NAN, NAN, home.alt_m + 2.5).result == ACCEPTED
    assert recv_text(gcs, lambda t: "arrived" in t, timeout=60) is not None
    assert command(gcs, M.MAV_CMD_NAV_RETURN_TO_LAUNCH).result == ACCEPTED
    assert _wait_mode(gcs, MD.AUTO, MD.AUTO_RTL)
    assert recv_text(gcs, lambda t: "landed" in t, timeout=90) is not None
    e, n, u = _position(gcs)
    assert math.hypot(e - hp.y, n - hp.x) < 0.2 and u < 0.1
    assert not _armed(gcs)
    # arming is refused in AUTO.RTL (MAVSDK switches to Hold first); reposition needs the rig armed
    _set_mode(gcs, "RTL")
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == DENIED
    assert recv_text(gcs, lambda t: "Arming denied: not in AUTO.RTL" in t) is not None


def test_prearm_refusals_and_recovery_from_a_failsafe_trip(rig, gcs):
    for m in range(3):  # three of five IMU modules stuck: no majority left, the estimate is invalid
        assert command(gcs, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, m, 1).result == ACCEPTED
    ack = command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert ack.result == DENIED
    assert recv_text(gcs, lambda t: t.startswith("Arming denied: IMU module 0 has an injected fault")) is not None
    for m in range(3):
        assert command(gcs, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, m, 0).result == ACCEPTED
    assert _until(gcs, lambda: command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED, 60)
    # a hard push trips the loss-of-control failsafe; the ideal plant then spins on: arming is refused
    assert command(gcs, M.MAV_CMD_HILMS_SHOCK, 1, 30.0, 0.3).result == ACCEPTED
    assert recv(gcs, "HEARTBEAT", 30, lambda m: m.system_status == M.MAV_STATE_EMERGENCY) is not None
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == DENIED
    assert recv_text(gcs, lambda t: "Arming denied: still rotating" in t or "Arming denied: not level" in t)
    # reboot brings the initial state back without restarting the process
    assert command(gcs, M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 1).result == ACCEPTED
    assert recv_text(gcs, lambda t: "rebooting" in t) is not None
    assert recv(gcs, "ATTITUDE", 10, lambda m: m.time_boot_ms < 2000 and abs(m.rollspeed) < 0.1) is not None
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED


def test_recovery_without_reboot_once_level_and_the_estimator_is_healthy(rig, gcs):
    _take_off(gcs, rig, alt=1.0)
    for m in range(3):  # the estimate goes invalid: the failsafe trips (estimate) and disarms, the rig stays level
        command(gcs, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, m, 2)
    assert recv(gcs, "HEARTBEAT", 30, lambda m: m.system_status == M.MAV_STATE_EMERGENCY) is not None
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == DENIED
    for m in range(3):
        command(gcs, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, m, 0)
    assert _until(gcs, lambda: command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED, 60)
    hb = recv(gcs, "HEARTBEAT", 10, lambda m: m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
    assert hb.system_status == M.MAV_STATE_ACTIVE  # the latch cleared on arming


def test_reboot_keeps_parameters_and_mission(rig, gcs):
    gcs.mav.param_set_send(1, 1, b"MPC_XY_CRUISE", 0.7, M.MAV_PARAM_TYPE_REAL32)
    assert recv(gcs, "PARAM_VALUE", 10, lambda m: m.param_id == "MPC_XY_CRUISE").param_value == pytest.approx(0.7)
    items = [MissionItem(0, ENU, M.MAV_CMD_NAV_TAKEOFF, z=1.0, current=1),
             MissionItem(1, ENU, M.MAV_CMD_NAV_WAYPOINT, x=1.0, z=1.0)]
    assert MissionClient(gcs).upload(items) == M.MAV_MISSION_ACCEPTED
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    assert command(gcs, M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 1).result == DENIED  # armed
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 0).result == ACCEPTED
    assert command(gcs, M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 2).result == UNSUPPORTED  # shutdown
    assert command(gcs, M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 1).result == ACCEPTED
    assert recv(gcs, "ATTITUDE", 10, lambda m: m.time_boot_ms < 2000) is not None
    gcs.mav.param_request_read_send(1, 1, b"MPC_XY_CRUISE", -1)
    assert recv(gcs, "PARAM_VALUE", 10, lambda m: m.param_id == "MPC_XY_CRUISE").param_value == pytest.approx(0.7)
    assert len(MissionClient(gcs).download()) == 2
    assert recv(gcs, "MISSION_CURRENT", 10, lambda m: m.mission_state == M.MISSION_STATE_NOT_STARTED)


def test_standard_modes_list_set_and_report(rig, gcs):
    ack = command(gcs, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AVAILABLE_MODES, 0)
    assert ack.result == ACCEPTED
    modes = {}
    while True:
        m = recv(gcs, "AVAILABLE_MODES", 5)
        modes[m.mode_index] = m
        if len(modes) == m.number_modes:
            break
    names = {m.mode_name for m in modes.values()}
    assert {"Position", "Hold", "Mission", "Return", "Land", "Takeoff", "Offboard", "Stabilized", "System ID"} == names
    by_std = {m.standard_mode: m.custom_mode for m in modes.values() if m.standard_mode}
    assert by_std[M.MAV_STANDARD_MODE_SAFE_RECOVERY] == MD.custom_mode(MD.AUTO, MD.AUTO_RTL)
    assert command(gcs, M.MAV_CMD_DO_SET_STANDARD_MODE, M.MAV_STANDARD_MODE_LAND).result == ACCEPTED
    cur = recv(gcs, "CURRENT_MODE", 10, lambda m: m.standard_mode == M.MAV_STANDARD_MODE_LAND)
    assert cur.custom_mode == MD.custom_mode(MD.AUTO, MD.AUTO_LAND)
    assert command(gcs, M.MAV_CMD_DO_SET_STANDARD_MODE, M.MAV_STANDARD_MODE_ORBIT).result == UNSUPPORTED
    assert recv_text(gcs, lambda t: "standard mode 2" in t and "SAFE_RECOVERY" in t) is not None
    assert command(gcs, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AVAILABLE_MODES, 99).result == DENIED


def test_change_speed_motor_test_and_land_start(rig, gcs):
    assert command(gcs, M.MAV_CMD_DO_CHANGE_SPEED, 1, 1.2, -1, 0).result == ACCEPTED
    assert command(gcs, M.MAV_CMD_DO_CHANGE_SPEED, 1, 500.0, -1, 0).result == DENIED
    ack = command(gcs, M.MAV_CMD_DO_MOTOR_TEST, 2, M.MOTOR_TEST_THROTTLE_PERCENT, 30, 1.0, 1, 0)
    assert ack.result == ACCEPTED
    servo = recv(gcs, "SERVO_OUTPUT_RAW", 10, lambda m: m.servo2_raw > 1200)
    assert servo is not None and servo.servo1_raw < 1100
    assert command(gcs, M.MAV_CMD_DO_MOTOR_TEST, 5, 0, 30, 1.0).result == DENIED
    assert command(gcs, M.MAV_CMD_DO_LAND_START).result == M.MAV_RESULT_FAILED
    assert recv_text(gcs, lambda t: "no DO_LAND_START" in t) is not None


def test_mission_items_jump_delay_and_return(rig, gcs):
    items = [MissionItem(0, ENU, M.MAV_CMD_NAV_TAKEOFF, z=1.0, current=1),
             MissionItem(1, ENU, M.MAV_CMD_NAV_WAYPOINT, x=0.5, z=1.0),
             MissionItem(2, ENU, M.MAV_CMD_NAV_WAYPOINT, x=0.0, y=0.5, z=1.0),
             MissionItem(3, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_JUMP, param1=1.0, param2=1.0),
             MissionItem(4, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_DELAY, param1=1.0),
             MissionItem(5, ENU, M.MAV_CMD_NAV_LOITER_TIME, param1=1.0, x=0.5, y=0.5, z=1.0),
             MissionItem(6, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_RETURN_TO_LAUNCH)]
    assert MissionClient(gcs).upload(items) == M.MAV_MISSION_ACCEPTED
    assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    assert command(gcs, M.MAV_CMD_MISSION_START, 0, 0).result == ACCEPTED
    reached = []
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and reached[-1:] != [5]:
        m = recv(gcs, "MISSION_ITEM_REACHED", 5)
        if m is not None:
            reached.append(m.seq)
    assert reached == [0, 1, 2, 1, 2, 4, 5]
    assert _wait_mode(gcs, MD.AUTO, MD.AUTO_RTL)
    assert recv_text(gcs, lambda t: "landed" in t, timeout=90) is not None
    assert not _armed(gcs)


def test_gcs_loss_lands_in_a_mode_that_needs_the_ground_station():
    with RigThread(speedup=4.0, overrides={"failsafe.gcs_timeout": 1.0, "failsafe.gcs_action": "land"}) as rig:
        gcs = connect(rig.tcp_url)
        try:
            gcs.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            _take_off(gcs, rig, alt=1.0, wait_loiter=False)  # ends in AUTO.LOITER: waits for the operator
            # silence: no more GCS heartbeats
            assert recv_text(gcs, lambda t: "ground station lost in AUTO.LOITER: failsafe land" in t, timeout=30)
            assert _wait_mode(gcs, MD.AUTO, MD.AUTO_LAND)
            assert recv_text(gcs, lambda t: "landed" in t, timeout=60) is not None
            gcs.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            assert recv_text(gcs, lambda t: "ground station regained" in t) is not None
        finally:
            gcs.close()


def test_hardware_rig_comes_to_rest_by_friction_after_a_loss_of_control_trip_and_rearms():
    """The default (hardware-faithful) plant: after a loss-of-control trip the motors stop, the
    joint's friction (joint.viscous, joint.coulomb) brings the pendulous rig to rest at its rest
    attitude (centre of gravity below the joint, inside ARM_MAX_TILT), and arming is accepted
    again without a reboot once it is still and the estimate is healthy."""
    with RigThread(speedup=8.0, airframe="hilms") as rig:
        gcs = connect(rig.tcp_url)
        gcs.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        try:
            assert _until(gcs, lambda: command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED, 60)
            assert command(gcs, M.MAV_CMD_HILMS_SHOCK, 1, 30.0, 0.3).result == ACCEPTED
            assert recv_text(gcs, lambda t: t.startswith("loss of control"), timeout=30) is not None
            assert recv(gcs, "HEARTBEAT", 10, lambda m: m.system_status == M.MAV_STATE_EMERGENCY) is not None
            spinning = recv(gcs, "ATTITUDE", 5)
            assert max(abs(spinning.rollspeed), abs(spinning.pitchspeed), abs(spinning.yawspeed)) > math.radians(20)
            assert command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == DENIED  # still rotating
            t_trip = recv(gcs, "ATTITUDE", 5).time_boot_ms
            assert _until(gcs, lambda: command(gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED, 120)
            att = recv(gcs, "ATTITUDE", 5)
            print(f"\nhilms: re-armed {(att.time_boot_ms - t_trip) / 1000:.1f} s (simulated) after the trip at roll "
                  f"{math.degrees(att.roll):.1f} deg, pitch {math.degrees(att.pitch):.1f} deg")
            assert max(abs(att.roll), abs(att.pitch)) < math.radians(20)
            hb = recv(gcs, "HEARTBEAT", 10, lambda m: m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
            assert hb.system_status == M.MAV_STATE_ACTIVE
        finally:
            gcs.close()
