"""MAVLink 2 signing on a live rig (real sockets, pymavlink clients with pymavlink's own signing):
signed telemetry, signed writes accepted, unsigned / wrongly signed / replayed / stale packets
rejected and counted, and a forged packet that cannot lock out the key holder."""

import hashlib
import time

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionItem
from rig_emulator.link.signing.clock import wall_timestamp
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv

KEY = hashlib.sha256(b"hilms rig 42").digest()
WRONG = hashlib.sha256(b"hilms rig 43").digest()
SIGNING = ("unsigned", "bad_signature", "replay", "stale_timestamp")


def _mission(n=3):
    return [MissionItem(seq=i, frame=M.MAV_FRAME_LOCAL_NED, command=M.MAV_CMD_NAV_WAYPOINT, x=float(i), y=0.5,
                        z=-1.0) for i in range(n)]


def _until(predicate, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return predicate()


def _rejected(rig) -> dict:
    return {r: rig.server.counters.dropped[r] for r in SIGNING if rig.server.counters.dropped[r]}


def _stamp(msg) -> int:
    return int.from_bytes(bytes(msg._msgbuf[-12:-6]), "little")


def _send_raw(conn, msg, enc=None) -> bytes:
    """Pack ``msg`` with pymavlink (``enc`` or the connection's own encoder and signing), send it on
    ``conn``, and return the bytes sent."""
    enc = enc or conn.mav
    buf = msg.pack(enc)
    enc.seq = (enc.seq + 1) % 256
    conn.write(buf)
    return buf


def test_key_holder_gets_signed_telemetry_and_is_obeyed():
    with RigThread(speedup=4.0, signing_key=KEY) as rig:
        good = connect(rig.tcp_url, signing_key=KEY)
        msgs = []
        deadline = time.monotonic() + 1.5
        while time.monotonic() < deadline:
            m = good.recv_match(blocking=True, timeout=0.2)
            if m is not None and m.get_type() != "BAD_DATA":
                msgs.append(m)
        assert len(msgs) > 20 and {"HEARTBEAT", "ATTITUDE"} <= {m.get_type() for m in msgs}
        assert all(m.get_signed() for m in msgs)  # checked against KEY by the client's pymavlink
        assert len({m._link_id for m in msgs}) == 1
        stamps = [_stamp(m) for m in msgs]
        assert all(b > a for a, b in zip(stamps, stamps[1:]))
        assert abs(stamps[-1] - wall_timestamp()) < 5 * 100_000  # 10 us units since 2015, the wall clock
        assert good.mav.signing.badsig_count == 0

        good.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.5, M.MAV_PARAM_TYPE_REAL32)
        assert recv(good, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.5
        assert rig.server.rig.cfg["smc.k"][0] == 2.5
        assert command(good, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        client = MissionClient(good)
        assert client.upload(_mission()) == M.MAV_MISSION_ACCEPTED
        assert [(i.x, i.y, i.z) for i in client.download()] == [(i.x, i.y, i.z) for i in _mission()]
        assert _rejected(rig) == {}
        good.close()


def _encoder(sysid: int, key: bytes | None = None):
    """A pymavlink encoder of our own: signs with ``key`` (or not) while the connection reads unchecked."""
    enc = M.MAVLink(None, srcSystem=sysid, srcComponent=190)
    if key is not None:
        enc.signing.secret_key, enc.signing.sign_outgoing, enc.signing.timestamp = key, True, wall_timestamp()
    return enc


def test_unsigned_and_wrong_key_writes_are_rejected_and_counted():
    with RigThread(speedup=4.0, signing_key=KEY) as rig:
        good = connect(rig.tcp_url, signing_key=KEY)
        assert MissionClient(good).upload(_mission(2)) == M.MAV_MISSION_ACCEPTED
        stored = rig.server.mission.items
        for sysid, name, key, words in ((250, "unsigned", None, "unsigned"),
                                        (251, "bad_signature", WRONG, "wrongly signed")):
            conn, enc = connect(rig.tcp_url, source_system=sysid), _encoder(sysid, key)
            assert recv(conn, "HEARTBEAT", 5) is not None  # the rig's signed telemetry is readable without a key
            before = rig.server.counters.dropped[name]
            for msg in (enc.command_long_encode(1, 1, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0),
                        enc.param_set_encode(1, 1, b"SMC_K_PHI", 3.0, M.MAV_PARAM_TYPE_REAL32),
                        enc.mission_count_encode(1, 1, 5, 0),
                        enc.param_request_list_encode(1, 1)):  # reads need the key too
                _send_raw(conn, msg, enc)
            text = recv(conn, "STATUSTEXT", 8, lambda m: m.text.startswith("signing: rejected"))  # first chunk
            assert text is not None and words in text.text
            assert _until(lambda: rig.server.counters.dropped[name] - before == 4), _rejected(rig)
            assert recv(conn, ["PARAM_VALUE", "MISSION_REQUEST_INT", "COMMAND_ACK"], 1.0) is None  # no answer
            assert rig.server.rig.cfg["smc.k"][0] == 1.47 and not rig.server.rig.snapshot().armed
            assert rig.server.mission.items == stored
            conn.close()
        assert set(_rejected(rig)) == {"unsigned", "bad_signature"}
        good.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.0, M.MAV_PARAM_TYPE_REAL32)  # the key holder still works
        assert recv(good, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.0
        good.close()


def test_replayed_packets_are_rejected_on_any_link():
    with RigThread(speedup=4.0, signing_key=KEY) as rig:
        good = connect(rig.tcp_url, signing_key=KEY)
        assert recv(good, "HEARTBEAT", 5) is not None
        recorded = _send_raw(good, good.mav.param_set_encode(1, 1, b"SMC_K_PHI", 2.0, M.MAV_PARAM_TYPE_REAL32))
        assert recv(good, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.0
        good.mav.param_set_send(1, 1, b"SMC_K_PHI", 3.0, M.MAV_PARAM_TYPE_REAL32)
        assert recv(good, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 3.0
        good.write(recorded)  # the same bytes again on the same link
        other = connect(rig.tcp_url)  # ... and on a new TCP connection
        other.write(recorded)
        assert _until(lambda: rig.server.counters.dropped["replay"] == 2), _rejected(rig)
        assert recv(good, "PARAM_VALUE", 1.0, lambda m: m.param_id == "SMC_K_PHI") is None
        assert rig.server.rig.cfg["smc.k"][0] == 3.0
        assert _rejected(rig) == {"replay": 2}
        good.close()
        other.close()


def test_forged_packets_cannot_lock_out_the_key_holder_and_stale_streams_are_refused():
    with RigThread(speedup=4.0, signing_key=KEY) as rig:
        good = connect(rig.tcp_url, signing_key=KEY)
        assert recv(good, "HEARTBEAT", 5) is not None
        # a wrong key on the key holder's own stream (same link id, system, component) an hour ahead:
        # pymavlink alone would record that timestamp and take every later genuine packet for a replay
        forger = connect(rig.tcp_url, signing_key=WRONG, link_id=good.mav.signing.link_id,
                         initial_timestamp=wall_timestamp() + 3600 * 100_000)
        forger.mav.param_set_send(1, 1, b"SMC_K_PHI", 9.0, M.MAV_PARAM_TYPE_REAL32)
        assert _until(lambda: rig.server.counters.dropped["bad_signature"] == 1)
        good.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.0, M.MAV_PARAM_TYPE_REAL32)
        assert recv(good, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.0
        # a new stream starting more than a minute in the past (an old recording, a host with a stale clock)
        stale = connect(rig.tcp_url, source_system=252, signing_key=KEY, initial_timestamp=wall_timestamp() - 120 * 100_000)
        stale.mav.param_set_send(1, 1, b"SMC_K_PHI", 4.0, M.MAV_PARAM_TYPE_REAL32)
        assert _until(lambda: rig.server.counters.dropped["stale_timestamp"] == 1), _rejected(rig)
        # unsigned RADIO_STATUS is accepted (and not acted on); SETUP_SIGNING, even signed, is not obeyed
        unsigned = connect(rig.tcp_url, source_system=253)
        unhandled = rig.server.counters.dropped["unhandled"]
        unsigned.mav.radio_status_send(200, 190, 50, 10, 5, 0, 0)
        assert _until(lambda: rig.server.counters.dropped["unhandled"] == unhandled + 1)
        good.mav.setup_signing_send(1, 1, list(WRONG), wall_timestamp())
        assert "SETUP_SIGNING ignored" in recv(good, "STATUSTEXT", 5, lambda m: "SETUP_SIGNING" in m.text).text
        good.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.5, M.MAV_PARAM_TYPE_REAL32)  # the key is unchanged
        assert recv(good, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.5
        assert rig.server.rig.cfg["smc.k"][0] == 2.5
        assert _rejected(rig) == {"bad_signature": 1, "stale_timestamp": 1}
        for c in (good, forger, stale, unsigned):
            c.close()
