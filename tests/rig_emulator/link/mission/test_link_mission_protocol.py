"""The mission protocol on the rig, driven by a pymavlink client over TCP: upload and download
in both message forms, pipelined / out-of-order / duplicated items, every refusal with its
MAV_MISSION_RESULT, atomic uploads (failed, cancelled, timed out), fence and rally types,
clear, set current, the item-0 convention parameter."""

import math
import time
from dataclasses import replace

import numpy as np
import pytest

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionItem, item_from_message, item_to_float_message, item_to_int_message
from rig_emulator.link.mission import transfer as mission_transfer
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv

LOCAL = M.MAV_FRAME_LOCAL_ENU
REL = M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def _wp(seq, x, y, z, frame=LOCAL, **kw):
    return MissionItem(seq=seq, frame=frame, command=M.MAV_CMD_NAV_WAYPOINT, x=x, y=y, z=z, **kw)


MISSION_A = [
    _wp(0, 0.0, 0.0, 1.0, current=1),
    MissionItem(seq=1, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_DO_CHANGE_SPEED, param1=1.0, param2=1.5, param3=-1.0),
    _wp(1 + 1, 1.25, -0.5, -1.0, frame=M.MAV_FRAME_LOCAL_NED, param1=0.5, param2=0.25),  # 1 m up (NED z down)
    _wp(3, 35.7000123, 51.4000456, 2.5, frame=REL),
    MissionItem(seq=4, frame=M.MAV_FRAME_GLOBAL_INT, command=M.MAV_CMD_NAV_LAND, x=0.0, y=0.0, z=0.0),
]
MISSION_B = [_wp(i, round(0.1 * i, 4), 0.0, 1.0) for i in range(7)]  # values MISSION_ITEM_INT carries


@pytest.fixture(scope="module")
def rig():
    with RigThread(speedup=1.0) as r:
        yield r


@pytest.fixture
def conn(rig):
    c = connect(rig.tcp_url)
    c.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    assert recv(c, "HEARTBEAT", 10) is not None
    yield c
    c.close()


def _ack(conn, timeout=5.0, mission_type=0):
    return recv(conn, "MISSION_ACK", timeout, lambda m: m.mission_type == mission_type)


def _upload(conn, items):
    return MissionClient(conn).upload(items)


def _download(conn):
    return MissionClient(conn).download()


def test_upload_download_round_trip_int_form(conn):
    assert _upload(conn, MISSION_A) == M.MAV_MISSION_ACCEPTED
    assert _download(conn) == MISSION_A


def test_float_form_and_old_style_requests(conn):
    """MISSION_ITEM upload (the rig then requests with MISSION_REQUEST), MISSION_REQUEST download."""
    items = [_wp(0, 35.7, 51.4, 2.0, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT), _wp(1, 1.0, 2.0, 3.0)]
    conn.mav.mission_count_send(1, 1, len(items), 0)
    first = recv(conn, ["MISSION_REQUEST_INT", "MISSION_REQUEST"], 5)
    assert first is not None and first.seq == 0
    conn.mav.send(item_to_float_message(items[0], 1, 1))
    second = recv(conn, ["MISSION_REQUEST_INT", "MISSION_REQUEST"], 5)
    assert second.get_type() == "MISSION_REQUEST" and second.seq == 1  # follows the peer's form
    conn.mav.send(item_to_float_message(items[1], 1, 1))
    assert _ack(conn).type == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_request_list_send(1, 1, 0)
    assert recv(conn, "MISSION_COUNT", 5).count == 2
    got = []
    for seq in range(2):
        conn.mav.mission_request_send(1, 1, seq, 0)
        m = recv(conn, ["MISSION_ITEM", "MISSION_ITEM_INT"], 5, lambda m: m.seq == seq)
        assert m.get_type() == "MISSION_ITEM"
        got.append(item_from_message(m))
    conn.mav.mission_ack_send(1, 1, 0, 0)
    f32 = [replace(it, x=float(np.float32(it.x)), y=float(np.float32(it.y))) for it in items]  # float32 on the wire
    assert got == f32


def test_pipelined_out_of_order_and_duplicated_items(conn):
    conn.mav.mission_count_send(1, 1, len(MISSION_B), 0)
    for seq in [3, 0, 0, 6, 5, 1, 3, 2, 4, 4]:  # pushed without waiting for requests
        conn.mav.send(item_to_int_message(MISSION_B[seq], 1, 1))
    assert _ack(conn).type == M.MAV_MISSION_ACCEPTED
    assert _download(conn) == MISSION_B


def test_lost_ack_is_repeated_for_a_late_duplicate_item(conn):
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.send(item_to_int_message(MISSION_B[-1], 1, 1))  # as if our ACK had been lost
    assert _ack(conn).type == M.MAV_MISSION_ACCEPTED


BAD = [
    (MissionItem(seq=1, frame=LOCAL, command=M.MAV_CMD_NAV_LOITER_TURNS, z=1.0), M.MAV_MISSION_UNSUPPORTED),
    (_wp(1, 0.0, 0.0, 1.0, frame=M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT), M.MAV_MISSION_UNSUPPORTED_FRAME),
    (_wp(1, 0.0, 0.0, 1.0, frame=M.MAV_FRAME_BODY_FRD), M.MAV_MISSION_UNSUPPORTED_FRAME),
    (_wp(1, 0.0, 0.0, 1.0, param1=-1.0), M.MAV_MISSION_INVALID_PARAM1),
    (_wp(1, 0.0, 0.0, 1.0, param2=-0.5), M.MAV_MISSION_INVALID_PARAM2),
    (_wp(1, 95.0, 51.4, 1.0, frame=REL), M.MAV_MISSION_INVALID_PARAM5_X),
    (_wp(1, 35.7, 200.0, 1.0, frame=REL), M.MAV_MISSION_INVALID_PARAM6_Y),
    (_wp(1, 0.0, 0.0, math.nan), M.MAV_MISSION_INVALID_PARAM7),
    (MissionItem(seq=1, frame=LOCAL, command=M.MAV_CMD_NAV_TAKEOFF, z=-1.0), M.MAV_MISSION_INVALID_PARAM7),
    (MissionItem(seq=1, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_DO_CHANGE_SPEED, param2=0.0),
     M.MAV_MISSION_INVALID_PARAM2),
    (_wp(9, 0.0, 0.0, 1.0), M.MAV_MISSION_INVALID_SEQUENCE),
]


@pytest.mark.parametrize("bad,result", BAD, ids=[str(r) + "-" + str(i) for i, (_, r) in enumerate(BAD)])
def test_bad_item_is_refused_and_the_previous_mission_stays(conn, bad, result):
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_count_send(1, 1, 3, 0)
    assert recv(conn, "MISSION_REQUEST_INT", 5, lambda m: m.seq == 0) is not None
    conn.mav.send(item_to_int_message(MISSION_A[0], 1, 1))
    assert recv(conn, "MISSION_REQUEST_INT", 5, lambda m: m.seq == 1) is not None
    conn.mav.send(item_to_int_message(bad, 1, 1))
    ack = _ack(conn)
    assert ack is not None and ack.type == result
    assert _download(conn) == MISSION_B


def test_too_many_items_no_space(conn):
    conn.mav.mission_count_send(1, 1, mission_transfer.MAX_ITEMS + 1, 0)
    assert _ack(conn).type == M.MAV_MISSION_NO_SPACE


def test_cancel_by_the_ground_station_keeps_the_mission(conn):
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_count_send(1, 1, 3, 0)
    assert recv(conn, "MISSION_REQUEST_INT", 5) is not None
    conn.mav.send(item_to_int_message(MISSION_A[0], 1, 1))
    conn.mav.mission_ack_send(1, 1, M.MAV_MISSION_OPERATION_CANCELLED, 0)
    time.sleep(0.2)
    assert _download(conn) == MISSION_B
    assert _upload(conn, MISSION_A) == M.MAV_MISSION_ACCEPTED  # a fresh upload is accepted at once


def test_timeout_retries_then_cancels_keeping_the_mission(conn, monkeypatch):
    monkeypatch.setattr(mission_transfer, "GIVE_UP_S", 1.0)
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_count_send(1, 1, 4, 0)
    requests = []
    ack = None
    deadline = time.monotonic() + 10
    while ack is None and time.monotonic() < deadline:
        m = recv(conn, ["MISSION_REQUEST_INT", "MISSION_ACK"], 5)
        if m is None:
            break
        if m.get_type() == "MISSION_ACK":
            ack = m
        else:
            requests.append(m.seq)
    assert ack is not None and ack.type == M.MAV_MISSION_OPERATION_CANCELLED
    assert len(requests) >= 3 and set(requests) == {0}, requests  # re-requested every RETRY_S
    assert _download(conn) == MISSION_B


def test_second_peer_is_denied_during_an_upload(rig, conn):
    other = connect(rig.tcp_url, source_system=254)
    try:
        other.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        conn.mav.mission_count_send(1, 1, 2, 0)
        assert recv(conn, "MISSION_REQUEST_INT", 5) is not None
        other.mav.mission_count_send(1, 1, 2, 0)
        assert _ack(other).type == M.MAV_MISSION_DENIED
        for it in MISSION_B[:2]:
            conn.mav.send(item_to_int_message(it, 1, 1))
        assert _ack(conn).type == M.MAV_MISSION_ACCEPTED
    finally:
        other.close()


@pytest.mark.parametrize("mtype", [M.MAV_MISSION_TYPE_FENCE, M.MAV_MISSION_TYPE_RALLY])
def test_fence_and_rally_are_answered(conn, mtype):
    conn.mav.mission_request_list_send(1, 1, mtype)
    count = recv(conn, "MISSION_COUNT", 5, lambda m: m.mission_type == mtype)
    assert count is not None and count.count == 0
    conn.mav.mission_count_send(1, 1, 2, mtype)
    assert _ack(conn, mission_type=mtype).type == M.MAV_MISSION_UNSUPPORTED
    conn.mav.mission_count_send(1, 1, 0, mtype)
    assert _ack(conn, mission_type=mtype).type == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_clear_all_send(1, 1, mtype)
    assert _ack(conn, mission_type=mtype).type == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_request_int_send(1, 1, 0, mtype)
    assert _ack(conn, mission_type=mtype).type == M.MAV_MISSION_INVALID_SEQUENCE


def test_request_beyond_the_mission_is_invalid_sequence(conn):
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_request_int_send(1, 1, len(MISSION_B), 0)
    assert _ack(conn).type == M.MAV_MISSION_INVALID_SEQUENCE


def test_clear_all_and_count_zero(conn):
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_clear_all_send(1, 1, 0)
    assert _ack(conn).type == M.MAV_MISSION_ACCEPTED
    assert _download(conn) == []
    cur = recv(conn, "MISSION_CURRENT", 5, lambda m: m.mission_state == M.MISSION_STATE_NO_MISSION)
    assert cur is not None and cur.total == 65535
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    assert _upload(conn, []) == M.MAV_MISSION_ACCEPTED
    assert _download(conn) == []


def test_set_current_by_message_and_command(conn):
    assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
    conn.mav.mission_set_current_send(1, 1, 4)
    cur = recv(conn, "MISSION_CURRENT", 5, lambda m: m.seq == 4)
    assert cur is not None and cur.total == len(MISSION_B) and cur.mission_state == M.MISSION_STATE_NOT_STARTED
    assert command(conn, M.MAV_CMD_DO_SET_MISSION_CURRENT, 2).result == M.MAV_RESULT_ACCEPTED
    assert recv(conn, "MISSION_CURRENT", 5, lambda m: m.seq == 2) is not None
    assert command(conn, M.MAV_CMD_DO_SET_MISSION_CURRENT, 99).result == M.MAV_RESULT_DENIED
    assert command(conn, M.MAV_CMD_MISSION_START, 0, 0).result == M.MAV_RESULT_DENIED  # disarmed
    # PX4 (and QGroundControl's "start mission"): AUTO.MISSION is taken disarmed, the mission flies on arming
    assert command(conn, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 4).result == M.MAV_RESULT_ACCEPTED
    assert recv(conn, "MISSION_CURRENT", 5, lambda m: m.mission_state == M.MISSION_STATE_NOT_STARTED) is not None
    assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
    cur = recv(conn, "MISSION_CURRENT", 5, lambda m: m.mission_state == M.MISSION_STATE_ACTIVE)
    assert cur is not None and cur.seq == 2


def test_item0_home_parameter(rig, conn):
    # the module's rig may still fly the mission an earlier test started: disarm, back to POSCTL
    assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 0).result == M.MAV_RESULT_ACCEPTED
    assert command(conn, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 3, 0).result == M.MAV_RESULT_ACCEPTED
    conn.mav.param_set_send(1, 1, b"MIS_ITEM0_HOME", 1.0, M.MAV_PARAM_TYPE_REAL32)
    assert recv(conn, "PARAM_VALUE", 5, lambda m: m.param_id == "MIS_ITEM0_HOME" and m.param_value == 1.0)
    try:
        assert _upload(conn, MISSION_B) == M.MAV_MISSION_ACCEPTED
        assert _download(conn) == MISSION_B  # item 0 stored and returned
        cur = recv(conn, "MISSION_CURRENT", 5, lambda m: m.total == len(MISSION_B) - 1)
        assert cur is not None and cur.seq == 1  # item 0 is home: the first item flown is 1
        assert rig.server.mission.plan.seqs == tuple(range(1, len(MISSION_B)))
    finally:
        conn.mav.param_set_send(1, 1, b"MIS_ITEM0_HOME", 0.0, M.MAV_PARAM_TYPE_REAL32)
        assert recv(conn, "PARAM_VALUE", 5, lambda m: m.param_id == "MIS_ITEM0_HOME" and m.param_value == 0.0)
