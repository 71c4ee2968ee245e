"""Geofence and mission plausibility over a real socket (pymavlink): uploads refused with the
MAV_MISSION result naming the field, a breach in flight acted on as FENCE_ACTION says,
DO_FENCE_ENABLE, FENCE_STATUS and SYS_STATUS's GEOFENCE bits."""

import math

import pytest

from protocol.dialect import mavlink as M
from protocol.mission_items import waypoint_items
from rig_emulator.link.commands.modes import AUTO, AUTO_LOITER, split_custom_mode
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, recv_text, start_offboard

POS = M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE | M.POSITION_TARGET_TYPEMASK_Z_IGNORE
REST = (M.POSITION_TARGET_TYPEMASK_AX_IGNORE | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
        | M.POSITION_TARGET_TYPEMASK_YAW_IGNORE | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE)
VEL = M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE


def _upload(conn, rig, points):
    return MissionClient(conn).upload(waypoint_items(points, rig.server.ctx.home))


def test_uploads_outside_the_fence_or_implausible_are_refused_naming_the_field():
    with RigThread(speedup=4.0, overrides={"fence.radius": 20.0, "fence.alt_max": 10.0}) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert _upload(conn, rig, [[0, 0, 2], [5, 0, 2], [5, 3, 2]]) == M.MAV_MISSION_ACCEPTED
        assert _upload(conn, rig, [[0, 0, 2], [0, 30, 2]]) == M.MAV_MISSION_INVALID_PARAM5_X
        assert recv_text(conn, lambda t: "item 1: 30.0 m from home, outside the fence radius 20 m" in t) is not None
        assert _upload(conn, rig, [[0, 0, 12]]) == M.MAV_MISSION_INVALID_PARAM7
        assert _upload(conn, rig, [[1, 1, -2]]) == M.MAV_MISSION_INVALID_PARAM7
        assert recv_text(conn, lambda t: "under the ground" in t) is not None
        assert len(rig.server.mission.items) == 3  # the refused uploads left the accepted mission as it was
        # with the fence off a 50 km leg is still refused (MIS_DIST_WPS)
        assert command(conn, M.MAV_CMD_DO_FENCE_ENABLE, 0).result == M.MAV_RESULT_ACCEPTED
        assert _upload(conn, rig, [[0, 0, 2], [50_000, 0, 2]]) == M.MAV_MISSION_INVALID_PARAM6_Y
        assert recv_text(conn, lambda t: "50.00 km leg" in t and "MIS_DIST_WPS" in t) is not None
        assert _upload(conn, rig, [[0, 0, 2], [0, 30, 2]]) == M.MAV_MISSION_ACCEPTED  # fence off: 30 m is fine
        assert command(conn, M.MAV_CMD_DO_FENCE_ENABLE, 2).result == M.MAV_RESULT_DENIED
        conn.close()


def test_breach_in_flight_holds_and_reports():
    with RigThread(speedup=8.0, overrides={"fence.alt_max": 1.5, "offboard.loss_timeout": 30.0}) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        sys_status = recv(conn, "SYS_STATUS", 5.0)
        assert sys_status.onboard_control_sensors_present & M.MAV_SYS_STATUS_GEOFENCE
        assert sys_status.onboard_control_sensors_enabled & M.MAV_SYS_STATUS_GEOFENCE
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        assert start_offboard(conn, lambda: conn.mav.set_position_target_local_ned_send(  # climb at 0.5 m/s
            0, 1, 1, M.MAV_FRAME_LOCAL_NED, POS | REST, 0, 0, 0, 0, 0, -0.5, 0, 0, 0, 0, 0)).result == 0
        got = recv_text(conn, lambda t: t.startswith("fence breach"), timeout=30.0)
        assert got is not None and "above the fence maximum 1.5 m" in got[1] and "hold" in got[1], got
        status = recv(conn, "FENCE_STATUS", 5.0)
        assert status.breach_status == 1 and status.breach_type == M.FENCE_BREACH_MAXALT and status.breach_count == 1
        hb = recv(conn, "HEARTBEAT", 5.0)
        assert split_custom_mode(hb.custom_mode) == (AUTO, AUTO_LOITER)
        unhealthy = recv(conn, "SYS_STATUS", 5.0, lambda m: not m.onboard_control_sensors_health & M.MAV_SYS_STATUS_GEOFENCE)
        assert unhealthy is not None
        for _ in range(2):
            recv(conn, "HEARTBEAT", 5.0)
        z1 = rig.server.rig.snapshot().position[2]
        recv(conn, "HEARTBEAT", 5.0)
        z2 = rig.server.rig.snapshot().position[2]
        assert z1 < 2.2 and abs(z2 - z1) < 0.05, (z1, z2)  # held just above 1.5 m, not climbing on
        conn.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0, M.MAVLINK_MSG_ID_FENCE_STATUS, 0, 0, 0, 0, 0, 0)
        assert recv(conn, "FENCE_STATUS", 5.0).breach_count == 1
        conn.close()


@pytest.mark.parametrize("action, expect", [("terminate", "disarmed"), ("return", "mode")])
def test_breach_actions(action, expect):
    with RigThread(speedup=8.0, overrides={"fence.radius": 1.0, "fence.action": action,
                                           "offboard.loss_timeout": 30.0}) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        assert start_offboard(conn, lambda: conn.mav.set_position_target_local_ned_send(
            0, 1, 1, M.MAV_FRAME_LOCAL_NED, VEL | REST, 3.0, 0, -1.0, 0, 0, 0, 0, 0, 0, 0, 0)).result == 0
        got = recv_text(conn, lambda t: t.startswith("fence breach"), timeout=30.0)
        assert got is not None and f"{action} (" in got[1] and expect in got[1], got
        if action == "terminate":
            assert recv(conn, "HEARTBEAT", 5.0, lambda m: not m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED) is not None
        conn.close()


def test_fence_parameters_are_served():
    with RigThread(speedup=4.0) as rig:
        conn = connect(rig.tcp_url)
        for name, value in (("FENCE_ENABLE", 1.0), ("FENCE_RADIUS", 100.0), ("FENCE_ALT_MAX", 50.0),
                            ("FENCE_ACTION", 2.0), ("COM_OF_LOSS_T", 1.0), ("MIS_DIST_WPS", 900.0)):
            conn.mav.param_request_read_send(1, 1, name.encode(), -1)
            m = recv(conn, "PARAM_VALUE", 5.0, lambda m, n=name: m.param_id == n)
            assert m is not None and math.isclose(m.param_value, value), name
        conn.close()
