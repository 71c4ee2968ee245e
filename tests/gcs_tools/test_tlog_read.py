"""gcs_tools.tlog_read walks a .tlog by frame length and decodes only the types asked for: it must
give exactly what pymavlink's own log reader gives (messages, sender, time stamps), skip damage
as pymavlink's robust parsing does, and count every message of the log."""

import random

import pytest
from pymavlink import mavutil

from gcs_tools.errors import UsageError
from gcs_tools.tlog_read import iter_tlog, read_fields
from protocol.dialect import mavlink as M
from protocol.dialect import use_hilms_dialect


def _write_log(path, n=300):
    """A small log of four message types from two systems, MAVLink 2 (and a few MAVLink 1) frames."""
    mavs = {1: M.MAVLink(None, srcSystem=1, srcComponent=1), 7: M.MAVLink(None, srcSystem=7, srcComponent=1)}
    v1 = M.MAVLink(None, srcSystem=1, srcComponent=1)
    v1.WIRE_PROTOCOL_VERSION = "1.0"
    with open(path, "wb") as f:
        for i in range(n):
            sysid = 7 if i % 5 == 4 else 1
            mav = v1 if i % 50 == 3 else mavs[sysid]
            msgs = [M.MAVLink_attitude_message(10 * i, 0.001 * i, -0.002 * i, 0.5, 0.0, 0.0, 0.0),
                    M.MAVLink_local_position_ned_message(10 * i, 0.01 * i, 0.0, -1.0, 0.0, 0.0, 0.0),
                    M.MAVLink_named_value_float_message(10 * i, b"LC1_N", 5.0 + i),
                    M.MAVLink_heartbeat_message(2, 12, 0, 0, 3, 3)]
            for k, m in enumerate(msgs):
                f.write((1_700_000_000_000_000 + 10_000 * i + k).to_bytes(8, "big") + m.pack(mav))


def _reference(path, types=None):
    use_hilms_dialect()
    log = mavutil.mavlogfile(str(path), robust_parsing=True)
    out = []
    while (m := log.recv_msg()) is not None:
        kind = m.get_type()
        if kind != "BAD_DATA" and not kind.startswith("UNKNOWN") and (types is None or kind in types):
            out.append((kind, m.get_srcSystem(), m._timestamp, m.to_dict()))
    return out


def _ours(path, types=None):
    return [(m.get_type(), m.get_srcSystem(), m._timestamp, m.to_dict()) for m in iter_tlog(path, types)]


def test_same_messages_as_pymavlink(tmp_path):
    path = tmp_path / "a.tlog"
    _write_log(path)
    assert _ours(path) == _reference(path) and len(_ours(path)) == 1200
    assert _ours(path, {"ATTITUDE", "NAMED_VALUE_FLOAT"}) == _reference(path, {"ATTITUDE", "NAMED_VALUE_FLOAT"})
    arrays, info = read_fields(path, {"ATTITUDE": ["time_boot_ms", "roll"], "NAMED_VALUE_FLOAT": ["LC1_N"]})
    assert info["messages"] == 1200 and info["sysid"] == 1 and info["counts"]["ATTITUDE"] == 240
    assert arrays["ATTITUDE"]["roll"][3] == pytest.approx(0.003)
    assert list(arrays["NAMED_VALUE_FLOAT"]["LC1_N"][:4]) == [5.0, 6.0, 7.0, 8.0]


def test_damaged_log_keeps_the_good_frames(tmp_path):
    path = tmp_path / "a.tlog"
    _write_log(path)
    data = bytearray(path.read_bytes())
    rng = random.Random(4)
    for _ in range(15):
        data[rng.randrange(len(data))] ^= 0x5A
    data[5000:5000] = b"\xfd\xfe garbage \xfd" * 7
    (tmp_path / "b.tlog").write_bytes(bytes(data[:-5]))
    ours, ref = _ours(tmp_path / "b.tlog"), _reference(tmp_path / "b.tlog")
    assert len(ours) > 1100
    assert len(set(map(repr, ours)) ^ set(map(repr, ref))) <= 5  # resynchronisation may differ at a damaged spot
    assert all(m in map(repr, ref) for m in map(repr, ours[-100:]))


def test_not_a_log(tmp_path):
    junk = tmp_path / "junk.tlog"
    junk.write_bytes(bytes(range(256)) * 20)
    with pytest.raises(UsageError, match="no MAVLink messages"):
        read_fields(junk, {"ATTITUDE": ["roll"]})
    with pytest.raises(UsageError, match="no such file"):
        read_fields(tmp_path / "none.tlog", {"ATTITUDE": ["roll"]})
    (tmp_path / "empty.tlog").write_bytes(b"")
    with pytest.raises(UsageError, match="no MAVLink messages"):
        read_fields(tmp_path / "empty.tlog", {"ATTITUDE": ["roll"]})
