"""Bad input never stops the rig: it is counted, dropped, and the streams keep their rate."""

import math
import os
import socket

import pytest

from protocol.dialect import mavlink as M
from rig_emulator.testing.rig import NAN, collect, command, count_in_window, recv, stamp_s


def _frame(msg, src=255):
    mav = M.MAVLink(None, srcSystem=src, srcComponent=190)
    return bytes(msg.pack(mav))


def test_garbage_bad_crc_truncated_and_foreign_messages(rig, client):
    counters = rig.server.counters
    sock = client.port  # the raw TCP socket of the pymavlink client
    good = _frame(M.MAVLink_command_long_message(1, 1, 31999, 0, *[NAN] * 7))
    bad_crc = bytearray(good)
    bad_crc[-1] ^= 0xFF
    truncated = good[: len(good) // 2]
    sock.sendall(os.urandom(4096).replace(b"\xfd", b"\x00").replace(b"\xfe", b"\x00"))
    sock.sendall(bytes(bad_crc))
    sock.sendall(truncated)
    sock.sendall(good * 3)  # resynchronises; the first copy may be eaten by the truncated frame, and
    # identical frames (same sequence number) are one command delivered twice: one ACK
    foreign = _frame(M.MAVLink_command_long_message(42, 1, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, *[NAN] * 6))
    other_comp = _frame(M.MAVLink_command_long_message(1, 99, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, *[NAN] * 6))
    sock.sendall(foreign + other_comp)
    client.mav.param_set_send(1, 1, b"SMC_BL", 1e9, M.MAV_PARAM_TYPE_REAL32)
    client.mav.set_position_target_local_ned_send(0, 1, 1, M.MAV_FRAME_LOCAL_NED, 0, NAN, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
    client.mav.set_attitude_target_send(0, 1, 1, 0, [0.0, 0.0, 0.0, 0.0], 0, 0, 0, 0.5)
    ack = recv(client, "COMMAND_ACK", condition=lambda m: m.command == 31999)
    assert ack is not None and ack.result == M.MAV_RESULT_UNSUPPORTED
    assert recv(client, "PARAM_VALUE", condition=lambda m: m.param_id == "SMC_BL").param_value == pytest.approx(0.05)
    assert command(client, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_HOME_POSITION).result == M.MAV_RESULT_ACCEPTED
    d = counters.dropped
    assert d["duplicate_command"] >= 1
    assert d["bad_prefix"] >= 1 and counters.bad_crc >= 1
    assert d["other_system"] == 1 and d["other_component"] == 1
    # the NaN x with its bit set and the zero attitude quaternion: refused set-points (STATUSTEXT + counter)
    assert d.get("setpoint_refused", 0) + d.get("invalid", 0) == 2, d
    assert d.get("handler_error", 0) == 0
    assert not rig.server.rig.snapshot().armed  # the foreign ARM commands did nothing
    got = collect(client, sim_seconds=6.0)
    stamps = sorted(stamp_s(m) for m in got["ATTITUDE"])
    t0, t1 = stamps[0] + 0.5, stamps[-1] - 0.5
    n = count_in_window(got["ATTITUDE"], t0, t1)
    assert abs(n - 25 * (t1 - t0)) <= 2
    sys_status = got["SYS_STATUS"][-1]
    assert sys_status.errors_comm > 0


def test_udp_garbage_flood_and_new_peers():
    """Datagram garbage from many sources: counted, the rig keeps serving its TCP client."""
    from rig_emulator.testing.rig import RigThread, connect

    with RigThread(speedup=4.0, extra_endpoints=["udpin:127.0.0.1:0"]) as r:
        udp_url = next(u for u in r.urls if u.startswith("udpin:"))
        port = int(udp_url.rsplit(":", 1)[1])
        socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(20)]
        for i in range(200):
            socks[i % 20].sendto(os.urandom(300), ("127.0.0.1", port))
        tcp = connect(r.tcp_url)
        assert command(tcp, 31999).result == M.MAV_RESULT_UNSUPPORTED
        got = collect(tcp, sim_seconds=3.0)
        assert len(got["ATTITUDE"]) >= 60
        assert r.server.counters.dropped["peer_limit"] >= 1
        assert math.isfinite(r.server.rig.snapshot().position[0])
        for s in socks:
            s.close()
        tcp.close()
