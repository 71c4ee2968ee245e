"""Hypothesis feeds the rig's receive path in-process (no sockets): generated MAVLink frames of
every message the rig handles, CRC-valid with arbitrary field values (NaN, infinities, float32
extremes, integer edges, random bytes in strings, unknown commands, negative indices), plus
truncated, bit-flipped, oversized and relabelled frames and garbage. The frames go through the
same Channel.receive + RigServer.handle path as bytes from a socket, then the loop steps and
streams. No handler may raise, every datagram is counted as the oracle says, and what the rig
stores (parameters, the mission) stays valid."""

import math
import struct
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from protocol.dialect import mavlink as M
from protocol.mission_items import validate_item
from rig_emulator.config.loader import check_value, load_config
from rig_emulator.config.schema import SCHEMA
from rig_emulator.link.endpoints.channel import Channel
from rig_emulator.link.serve import prepare_rig
from rig_emulator.link.server import RigServer
from rig_emulator.link.telemetry.stream_table import ON_REQUEST, default_rates
from rig_emulator.link.telemetry.streams import StreamSchedule
from rig_emulator.testing.fuzz import (
    COMMANDS, FRAMES, HANDLED_TYPES, INT_RANGES, ITEM_COMMANDS, PARAM_NAMES, UNKNOWN_IDS, crc_of, expected_counts,
)

PARSE_KEYS = ("received", "bad_crc", "bad_prefix", "bad_data", "truncated", "unknown_id", "own_echo",
              "other_system", "other_component", "unhandled")


class CaptureEndpoint:
    """What a UDP endpoint is to a channel, keeping what the rig sends in memory."""

    kind = "udpin"
    datagram = True

    def __init__(self):
        self.sent = 0

    def send(self, key, data) -> bool:
        self.sent += 1
        return True

    def flush(self) -> None:
        pass


@pytest.fixture(scope="module")
def link():
    server = RigServer(prepare_rig(load_config()), [], speedup=1.0)
    channel = Channel(CaptureEndpoint(), ("127.0.0.1", 14550), server.sysid, 1, server.counters,
                      StreamSchedule(default_rates(), server.chunk_s))
    server.channels[("capture", 0)] = channel
    yield server, channel
    print("\nin-process fuzz counters:", server.counters.as_dict(), "commands ACKed", server.counters.commands)
    server.close()


def test_handled_types_match_the_server(link):
    server, _ = link
    assert set(HANDLED_TYPES) == set(server._handlers)


# --- strategies -----------------------------------------------------------------------------------------

def field_values(ftype: str, length: int):
    if ftype == "char":
        return st.binary(max_size=length)
    if ftype == "float":
        one = st.floats(width=32)  # NaN, +-inf, subnormals, +-3.4e38 included
    elif ftype == "double":
        one = st.floats()
    else:
        one = st.integers(*INT_RANGES[ftype])
    return st.lists(one, min_size=length, max_size=length) if length else one


def mostly(*good, other):
    """``good`` values (each as likely as ``other``'s whole range: hypothesis picks branches evenly)."""
    return st.one_of(*(st.just(v) for v in good), other)


BIASED = {
    "target_system": mostly(1, 1, 1, 0, other=st.integers(0, 255)),
    "target_component": mostly(1, 1, 1, 0, other=st.integers(0, 255)),
    "mission_type": st.sampled_from([0, 1, 2, 255]) | st.integers(0, 255),
    ("COMMAND_LONG", "command"): st.sampled_from(COMMANDS) | st.integers(0, 65535),
    ("COMMAND_INT", "command"): st.sampled_from(COMMANDS) | st.integers(0, 65535),
    ("MISSION_ITEM", "command"): st.sampled_from(ITEM_COMMANDS) | st.integers(0, 65535),
    ("MISSION_ITEM_INT", "command"): st.sampled_from(ITEM_COMMANDS) | st.integers(0, 65535),
    ("MISSION_ITEM", "frame"): st.sampled_from(FRAMES) | st.integers(0, 255),
    ("MISSION_ITEM_INT", "frame"): st.sampled_from(FRAMES) | st.integers(0, 255),
    ("PARAM_SET", "param_id"): st.sampled_from(PARAM_NAMES) | st.binary(max_size=16),
    ("PARAM_REQUEST_READ", "param_id"): st.sampled_from(PARAM_NAMES) | st.binary(max_size=16),
    ("PARAM_REQUEST_READ", "param_index"): st.sampled_from([-1, 0, 119, 120]) | st.integers(-32768, 32767),
    ("SET_POSITION_TARGET_LOCAL_NED", "coordinate_frame"): st.just(M.MAV_FRAME_LOCAL_NED) | st.integers(0, 255),
    ("MISSION_COUNT", "count"): st.sampled_from([0, 1, 3, 10_001]) | st.integers(0, 65535),
}
for name in ("param1", "param2", "param3", "param4"):  # commands: small whole numbers reach the handlers
    for msg in ("COMMAND_LONG", "COMMAND_INT"):
        BIASED[(msg, name)] = st.sampled_from([0.0, 1.0, 2.0, 4.0, -1.0, 252.0]) | st.floats(width=32)


def _handled_classes():
    return [c for c in M.mavlink_map.values() if c.msgname in HANDLED_TYPES]


@st.composite
def messages(draw, classes):
    cls = draw(st.sampled_from(sorted(classes, key=lambda c: c.id)))
    values = []
    for name, ftype in zip(cls.fieldnames, cls.fieldtypes):
        length = cls.array_lengths[cls.ordered_fieldnames.index(name)]
        key = (cls.msgname, name) if (cls.msgname, name) in BIASED else name
        strategy = BIASED[key] if key in BIASED else field_values(ftype, length)
        values.append(draw(strategy))
    return cls(*values)


@st.composite
def datagrams(draw):
    """One datagram: a pymavlink-packed frame, maybe corrupted, or garbage."""
    kind = draw(st.sampled_from(["valid", "valid", "valid", "other", "v1", "truncated", "bitflip", "oversized",
                                 "unknown_id", "garbage"]))
    if kind == "garbage":
        return draw(st.binary(min_size=1, max_size=400))
    classes = [c for c in M.mavlink_map.values() if c.msgname not in HANDLED_TYPES] if kind == "other" \
        else _handled_classes()
    if kind == "v1":
        classes = [c for c in classes if c.id < 256]
    msg = draw(messages(classes))
    src = draw(mostly((255, 190), (255, 190), (255, 190), (1, 1), other=st.tuples(st.integers(0, 255), st.integers(0, 255))))
    mav = M.MAVLink(None, srcSystem=src[0], srcComponent=src[1])
    mav.seq = draw(st.integers(0, 255))
    frame = bytearray(msg.pack(mav, force_mavlink1=kind == "v1"))
    if kind == "truncated":
        return bytes(frame[: draw(st.integers(1, len(frame) - 1))])
    if kind == "bitflip":
        for pos in draw(st.lists(st.integers(0, len(frame) - 1), min_size=1, max_size=4)):
            frame[pos] ^= 1 << draw(st.integers(0, 7))
    elif kind == "oversized" and frame[0] == M.PROTOCOL_MARKER_V2 and frame[1] < 255:
        extra = draw(st.binary(min_size=1, max_size=255 - frame[1]))
        body = bytearray(frame[:-2]) + extra
        body[1] += len(extra)
        frame = body + struct.pack("<H", crc_of(bytes(body), msg.crc_extra))
    elif kind == "unknown_id" and frame[0] == M.PROTOCOL_MARKER_V2:
        frame[7:10] = draw(st.sampled_from(UNKNOWN_IDS)).to_bytes(3, "little")
    return bytes(frame)


# --- invariants -------------------------------------------------------------------------------------------

def _stored_state_is_valid(server) -> None:
    cfg = server.rig.cfg
    for key in {p.key for p in server.params.table.params if not getattr(p, "read_only", False)}:  # derived: no config key
        value = cfg[key]
        check_value(key, SCHEMA[key], list(value) if isinstance(value, tuple) else value)
    for item in server.mission.items:
        assert validate_item(item, server.ctx.home)[0] == M.MAV_MISSION_ACCEPTED, item


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                   HealthCheck.too_slow, HealthCheck.data_too_large])
@given(batch=st.lists(datagrams(), min_size=1, max_size=12))
def test_generated_frames_never_break_the_rig(link, batch):
    server, channel = link
    counters = server.counters
    before = counters.as_dict()
    expected = sum((expected_counts(d, server.sysid, 1) for d in batch), start=type(expected_counts(b"", 1, 1))())
    for data in batch:
        for msg in channel.receive(data):
            server.handle(msg, channel)
    after = counters.as_dict()
    assert after["dropped"].get("handler_error", 0) == 0, "a handler raised"

    def delta(key):
        if key == "received":
            return after["received"] - before["received"]
        return after["dropped"].get(key, 0) - before["dropped"].get(key, 0)

    assert {k: delta(k) for k in PARSE_KEYS} == {k: expected.get(k, 0) for k in PARSE_KEYS}
    assert after["rx_bytes"] - before["rx_bytes"] == expected["rx_bytes"]
    assert after["bad_bytes"] - before["bad_bytes"] == expected["bad_bytes"]
    server.mission_transfer.tick(time.monotonic())
    server.step_chunk()
    server.emit_streams()
    _stored_state_is_valid(server)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
def test_telemetry_encodes_a_diverged_simulation(link):
    """Every stream and on-request message still encodes when the state is NaN, inf or beyond float32
    (schema-valid parameters such as AF_MASS = 1e-27 kg make the virtual position diverge)."""
    server, channel = link
    sim = server.rig.sim
    saved = (sim.x.copy(), sim.sensing.state.onboard.copy(), sim.sensing.state.att_est.copy())
    sent = channel.endpoint.sent
    try:
        for value in (1e39, -1e300, math.nan, math.inf, -math.inf):
            sim.x[:] = value
            sim.sensing.state.onboard[:] = value
            sim.sensing.state.att_est[:] = value
            for msg_id in ON_REQUEST:
                for msg in server.build(msg_id):
                    channel.send(msg)
    finally:
        sim.x[:], sim.sensing.state.onboard[:], sim.sensing.state.att_est[:] = saved
        server._snap = None
    assert channel.endpoint.sent - sent >= 5 * len(ON_REQUEST)
