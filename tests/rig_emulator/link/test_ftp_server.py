"""The read-only MAVFTP server (rig_emulator/link/ftp/server.py), request by request."""

import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rig_emulator.link.ftp import server as F

HEADER = struct.Struct("<HBBBBBBI")


def req(opcode, seq=1, session=0, size=None, offset=0, data=b""):
    size = len(data) if size is None else size
    return HEADER.pack(seq, session, opcode, size, 0, 0, 0, offset) + data


def parse(payload):
    seq, session, opcode, size, req_op, burst, _p, offset = HEADER.unpack_from(payload)
    return dict(seq=seq, session=session, opcode=opcode, size=size, req=req_op, burst=burst, offset=offset,
                data=payload[HEADER.size:HEADER.size + size])


@pytest.fixture
def srv():
    body = bytes(range(256)) * 4  # 1024 bytes
    return F.FtpServer(F.FileStore({"metadata/general.json": b'{"version": 1}', "metadata/big.bin": body}))


def test_list_root_and_directory(srv):
    (r,) = srv.handle(req(F.OP_LIST_DIRECTORY, data=b"/"))
    r = parse(r)
    assert r["opcode"] == F.OP_ACK and r["seq"] == 2 and r["data"] == b"Dmetadata\0"
    (r,) = srv.handle(req(F.OP_LIST_DIRECTORY, seq=3, data=b"/metadata"))
    assert parse(r)["data"].split(b"\0")[:2] == [b"Fbig.bin\t1024", b"Fgeneral.json\t14"]
    (r,) = srv.handle(req(F.OP_LIST_DIRECTORY, seq=5, data=b"/metadata", offset=2))
    assert parse(r)["opcode"] == F.OP_NAK and parse(r)["data"] == bytes([F.ERR_EOF])
    (r,) = srv.handle(req(F.OP_LIST_DIRECTORY, seq=7, data=b"/nothing"))
    assert parse(r)["data"] == bytes([F.ERR_FILE_NOT_FOUND])


def test_open_read_burst_terminate(srv):
    (r,) = srv.handle(req(F.OP_OPEN_FILE_RO, data=b"/metadata/big.bin"))
    r = parse(r)
    assert r["opcode"] == F.OP_ACK and struct.unpack("<I", r["data"])[0] == 1024
    session = r["session"]
    (r,) = srv.handle(req(F.OP_READ_FILE, seq=3, session=session, size=100, offset=1000))
    assert parse(r)["data"] == (bytes(range(256)) * 4)[1000:]
    (r,) = srv.handle(req(F.OP_READ_FILE, seq=5, session=session, size=100, offset=1024))
    assert parse(r)["data"] == bytes([F.ERR_EOF])
    replies = [parse(x) for x in srv.handle(req(F.OP_BURST_READ_FILE, seq=7, session=session, size=239, offset=0))]
    assert b"".join(x["data"] for x in replies) == bytes(range(256)) * 4
    assert [x["burst"] for x in replies] == [0, 0, 0, 0, 1] and replies[-1]["size"] < 239
    assert [x["seq"] for x in replies] == [8, 9, 10, 11, 12]  # consecutive: MAVSDK drops repeated seqs
    (r,) = srv.handle(req(F.OP_TERMINATE_SESSION, seq=9, session=session))
    assert parse(r)["opcode"] == F.OP_ACK
    (r,) = srv.handle(req(F.OP_READ_FILE, seq=11, session=session, size=10))
    assert parse(r)["data"] == bytes([F.ERR_INVALID_SESSION])


def test_everything_else_is_nakd_with_the_spec_errors(srv):
    (r,) = srv.handle(req(F.OP_OPEN_FILE_RO, data=b"@PARAM/param.pck?withdefaults=1"))
    assert parse(r)["data"] == bytes([F.ERR_FILE_NOT_FOUND])  # MAVProxy then falls back to PARAM_REQUEST_LIST
    for seq, op in enumerate(sorted(F.WRITE_OPS)):
        (r,) = srv.handle(req(op, seq=100 + 2 * seq, data=b"/x"))
        assert parse(r)["opcode"] == F.OP_NAK and parse(r)["data"] == bytes([F.ERR_FILE_PROTECTED])
    (r,) = srv.handle(req(F.OP_CALC_FILE_CRC32, seq=200, data=b"/metadata/big.bin"))
    assert parse(r)["data"] == bytes([F.ERR_UNKNOWN_COMMAND])
    (r,) = srv.handle(req(99, seq=202))
    assert parse(r)["data"] == bytes([F.ERR_UNKNOWN_COMMAND])


def test_sessions_run_out_and_reset(srv):
    for i in range(F.MAX_SESSIONS):
        assert parse(srv.handle(req(F.OP_OPEN_FILE_RO, seq=2 * i, data=b"metadata/general.json"))[0])["opcode"] == F.OP_ACK
    (r,) = srv.handle(req(F.OP_OPEN_FILE_RO, seq=50, data=b"metadata/general.json"))
    assert parse(r)["data"] == bytes([F.ERR_NO_SESSIONS_AVAILABLE])
    assert parse(srv.handle(req(F.OP_RESET_SESSIONS, seq=52))[0])["opcode"] == F.OP_ACK
    assert not srv.sessions


def test_a_repeated_request_is_answered_again_without_acting_twice(srv):
    first = srv.handle(req(F.OP_OPEN_FILE_RO, seq=40, data=b"metadata/general.json"), "peer")
    again = srv.handle(req(F.OP_OPEN_FILE_RO, seq=40, data=b"metadata/general.json"), "peer")
    assert first == again and len(srv.sessions) == 1


@given(st.binary(max_size=260))
def test_garbage_never_raises(payload):
    srv = F.FtpServer(F.FileStore({"a": b"x"}))
    out = srv.handle(payload)
    assert out is None or all(len(p) <= F.PAYLOAD_LEN for p in out)


def test_a_new_request_with_an_old_seq_is_not_taken_for_a_retry(srv):
    # MAVProxy starts every operation at seq 0: its open of param.pck, then of a metadata file
    (r,) = srv.handle(req(F.OP_OPEN_FILE_RO, seq=0, data=b"@PARAM/param.pck"), "peer")
    assert parse(r)["opcode"] == F.OP_NAK
    (r,) = srv.handle(req(F.OP_OPEN_FILE_RO, seq=0, data=b"/metadata/general.json"), "peer")
    assert parse(r)["opcode"] == F.OP_ACK
