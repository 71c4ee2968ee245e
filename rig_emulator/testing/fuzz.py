"""Hostile input for the rig's receive path (fuzzing), and the oracle of how the rig counts it.

:class:`FrameFactory` makes datagrams from a seeded random generator, every valid frame built
and packed by pymavlink's generated dialect, then corrupted where a kind asks for it:

* ``valid`` - a CRC-valid frame of a message the rig acts on (:data:`HANDLED_TYPES`) with
  random field values: NaN, infinities, huge and negative numbers, integer edges, random
  bytes in strings, with a bias towards what reaches the handlers (the rig's system and
  component ids, supported commands, real parameter names, small sequence numbers);
* ``other`` - a CRC-valid frame of any other message of the dialect (the rig ignores it),
  MAVLink 1 framing when the id allows;
* ``bad_crc`` - a valid frame with one bit of its payload or checksum flipped;
* ``truncated`` - a valid frame cut short;
* ``oversized`` - a valid frame whose length byte claims more payload than the message has,
  padded with random bytes, with the checksum recomputed (CRC-valid) or not;
* ``unknown_id`` - a valid frame relabelled with a message id the dialect does not define;
* ``bitflip`` - a valid frame with a few bits flipped anywhere, header included;
* ``garbage`` - random bytes (1 to 600).

:func:`expected_counts` says what the rig must count for one datagram, with a fresh pymavlink
parser and the rig's dispatch rules (a UDP datagram is parsed on its own: a frame cannot span
datagrams); :class:`StreamOracle` does the same for a TCP byte stream. Keys are the rig's
counter names (:mod:`rig_emulator.link.endpoints.counters`).
"""

from __future__ import annotations

import math
import random
import struct
from collections import Counter

from protocol.dialect import mavlink as M

#: the messages the rig acts on (kept equal to RigServer's handler table by a test)
HANDLED_TYPES = (
    "HEARTBEAT", "PARAM_REQUEST_LIST", "PARAM_REQUEST_READ", "PARAM_SET", "COMMAND_LONG", "COMMAND_INT", "SET_MODE",
    "REQUEST_DATA_STREAM", "SET_POSITION_TARGET_LOCAL_NED", "SET_POSITION_TARGET_GLOBAL_INT", "SET_ATTITUDE_TARGET",
    "SET_ACTUATOR_CONTROL_TARGET", "TIMESYNC",
    "FILE_TRANSFER_PROTOCOL", "MISSION_COUNT", "MISSION_ITEM", "MISSION_ITEM_INT", "MISSION_REQUEST_LIST",
    "MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK", "MISSION_CLEAR_ALL", "MISSION_SET_CURRENT",
    "SETUP_SIGNING",
)

KINDS = {  # kind: weight
    "valid": 40, "other": 8, "bad_crc": 12, "truncated": 10, "oversized": 10, "unknown_id": 5, "bitflip": 5,
    "garbage": 10,
}

SPECIAL_FLOATS = (math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 3.0, 4.0, 10.0, 100.0, 1e6, -1e6,
                  1e30, -1e30, 3.4e38, -3.4e38, 1.4e-45, 65535.0, 2.0**31, -(2.0**31), 1e10)
INT_RANGES = {
    "uint8_t": (0, 2**8 - 1), "int8_t": (-(2**7), 2**7 - 1), "uint16_t": (0, 2**16 - 1), "int16_t": (-(2**15), 2**15 - 1),
    "uint32_t": (0, 2**32 - 1), "int32_t": (-(2**31), 2**31 - 1), "uint64_t": (0, 2**64 - 1),
    "int64_t": (-(2**63), 2**63 - 1), "uint8_t_mavlink_version": (0, 255),
}
COMMANDS = (
    M.MAV_CMD_COMPONENT_ARM_DISARM, M.MAV_CMD_DO_SET_MODE, M.MAV_CMD_REQUEST_MESSAGE,
    M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAV_CMD_GET_MESSAGE_INTERVAL,
    M.MAV_CMD_GET_HOME_POSITION, M.MAV_CMD_PREFLIGHT_CALIBRATION, M.MAV_CMD_HILMS_SHOCK, M.MAV_CMD_HILMS_EXTRA_MASS,
    M.MAV_CMD_HILMS_SENSOR_FAULT, M.MAV_CMD_MISSION_START, M.MAV_CMD_DO_SET_MISSION_CURRENT, M.MAV_CMD_DO_FENCE_ENABLE,
    M.MAV_CMD_HILMS_SYSID,
)
ITEM_COMMANDS = (M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_NAV_TAKEOFF, M.MAV_CMD_NAV_LAND, M.MAV_CMD_NAV_LOITER_TIME,
                 M.MAV_CMD_DO_CHANGE_SPEED, M.MAV_CMD_NAV_RETURN_TO_LAUNCH, M.MAV_CMD_HILMS_SYSID)
FRAMES = (M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_INT,
          M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_FRAME_LOCAL_ENU, M.MAV_FRAME_MISSION)
PARAM_NAMES = (b"SMC_K_PHI", b"SMC_BL", b"WP_RADIUS", b"CTL_STRATEGY", b"SIM_PHYS_HZ", b"AF_MASS", b"MIS_ITEM0_HOME",
               b"SENS_SIMULATE", b"EST_LC_FILTER", b"FLC_GEOMETRY", b"DIST_WIND_X", b"MPC_XY_CRUISE", b"PID_ATT_KP_PHI")
V2_HEADER = M.HEADER_LEN_V2


def _unknown_ids() -> list[int]:
    known = set(M.mavlink_map)
    return [i for i in (2, 3, 9, 10, 13, 200, 255, 1000, 4000, 12345, 58110, 65535, 2**20, 2**24 - 1) if i not in known]


UNKNOWN_IDS = _unknown_ids()


def crc_of(frame_wo_crc: bytes, crc_extra: int) -> int:
    """The X.25 checksum pymavlink computes over a frame (header after STX, payload) plus CRC_EXTRA."""
    crc = M.x25crc(frame_wo_crc[1:])
    crc.accumulate([crc_extra])
    return crc.crc


class FrameFactory:
    """Datagrams of every kind in :data:`KINDS`, reproducible from ``seed``."""

    def __init__(self, seed: int = 0, sysid: int = 1, compid: int = 1, src=(255, 190), kinds: dict | None = None):
        self.rng = random.Random(seed)
        self.sysid, self.compid = sysid, compid
        self.src = src
        self._mavs: dict = {}
        classes = sorted(M.mavlink_map.values(), key=lambda c: c.id)
        self.handled = [c for c in classes if c.msgname in HANDLED_TYPES]
        self.others = [c for c in classes if c.msgname not in HANDLED_TYPES]
        kinds = kinds or KINDS
        self.kind_names = list(kinds)
        self.kind_weights = [kinds[k] for k in self.kind_names]

    # --- values --------------------------------------------------------------------------------
    def float_value(self, ftype: str = "float") -> float:
        r = self.rng.random()
        if r < 0.4:
            return self.rng.choice(SPECIAL_FLOATS) if ftype == "double" else _as_f32(self.rng.choice(SPECIAL_FLOATS))
        if r < 0.7:
            return _as_f32(self.rng.uniform(-1000.0, 1000.0))
        if ftype == "double":
            return struct.unpack("<d", self.rng.randbytes(8))[0]
        return struct.unpack("<f", self.rng.randbytes(4))[0]

    def int_value(self, ftype: str) -> int:
        lo, hi = INT_RANGES[ftype]
        r = self.rng.random()
        if r < 0.4:
            return self.rng.choice([v for v in (lo, hi, 0, 1, -1, 2, hi // 2) if lo <= v <= hi])
        if r < 0.7:
            return self.rng.randint(max(lo, -10), min(hi, 300))
        return self.rng.randint(lo, hi)

    def text_value(self, length: int) -> bytes:
        r = self.rng.random()
        if r < 0.3 and length == 16:
            return self.rng.choice(PARAM_NAMES)
        if r < 0.6:
            return bytes(self.rng.randint(32, 126) for _ in range(self.rng.randint(0, length)))
        return self.rng.randbytes(self.rng.randint(0, length))

    def field_value(self, ftype: str, length: int):
        if ftype == "char":
            return self.text_value(length)
        one = (lambda: self.float_value(ftype)) if ftype in ("float", "double") else (lambda: self.int_value(ftype))
        return [one() for _ in range(length)] if length else one()

    # --- messages ----------------------------------------------------------------------------------
    def message(self, cls):
        """An instance of ``cls`` with random field values (biased towards the rig's handlers)."""
        values = {}
        for name, ftype in zip(cls.fieldnames, cls.fieldtypes):
            length = cls.array_lengths[cls.ordered_fieldnames.index(name)]  # array_lengths is in wire order
            values[name] = self.field_value(ftype, length)
        self._bias(cls.msgname, values)
        return cls(*(values[n] for n in cls.fieldnames))

    def _pick(self, p: float, choices, current):
        return self.rng.choice(choices) if self.rng.random() < p else current

    def _bias(self, name: str, v: dict) -> None:
        if "target_system" in v:
            v["target_system"] = self._pick(0.85, (self.sysid, self.sysid, 0), v["target_system"])
        if "target_component" in v:
            v["target_component"] = self._pick(0.85, (self.compid, self.compid, 0), v["target_component"])
        if "mission_type" in v:
            v["mission_type"] = self._pick(0.8, (0, 0, 0, 1, 2, 255), v["mission_type"])
        if name in ("COMMAND_LONG", "COMMAND_INT"):
            v["command"] = self._pick(0.75, COMMANDS, v["command"])
            small = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, -1.0, math.nan, 0.5, float(M.MAVLINK_MSG_ID_NAMED_VALUE_INT)]
            for p in ("param1", "param2", "param3", "param4"):
                v[p] = self._pick(0.5, small, v[p])
        if name in ("MISSION_ITEM", "MISSION_ITEM_INT"):
            v["command"] = self._pick(0.8, ITEM_COMMANDS, v["command"])
            v["frame"] = self._pick(0.8, FRAMES, v["frame"])
        if name in ("MISSION_ITEM", "MISSION_ITEM_INT", "MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_SET_CURRENT"):
            v["seq"] = self._pick(0.7, (0, 1, 2, 3, 5, 9, 65535), v["seq"])
        if name == "MISSION_COUNT":
            v["count"] = self._pick(0.7, (0, 1, 2, 3, 10, 10001, 65535), v["count"])
        if name == "PARAM_REQUEST_READ":
            v["param_index"] = self._pick(0.6, (-1, 0, 5, 120, 32767, -32768), v["param_index"])
        if name == "SET_POSITION_TARGET_LOCAL_NED":
            v["coordinate_frame"] = self._pick(0.8, (M.MAV_FRAME_LOCAL_NED,), v["coordinate_frame"])
            v["type_mask"] = self._pick(0.7, (0, 0b0000_1101_1111_1000, 0x400), v["type_mask"])
        if name == "SET_ATTITUDE_TARGET":
            v["type_mask"] = self._pick(0.7, (0, 7), v["type_mask"])
            if self.rng.random() < 0.5:
                v["q"] = [_as_f32(self.rng.uniform(-1, 1)) for _ in range(4)]
        if name == "REQUEST_DATA_STREAM":
            v["req_stream_id"] = self._pick(0.7, (0, 1, 2, 3, 6, 10, 11, 12), v["req_stream_id"])

    def _mav(self, src):
        if src not in self._mavs:
            self._mavs[src] = M.MAVLink(None, srcSystem=src[0], srcComponent=src[1])
        return self._mavs[src]

    def _source(self):
        r = self.rng.random()
        if r < 0.9:
            return self.src
        if r < 0.95:
            return (self.sysid, self.compid)  # the rig's own ids: an echo
        return (self.rng.randint(0, 255), self.rng.randint(0, 255))

    def pack(self, msg, mavlink1: bool = False) -> bytes:
        mav = self._mav(self._source())
        buf = bytes(msg.pack(mav, force_mavlink1=mavlink1))
        mav.seq = (mav.seq + 1) % 256
        return buf

    def valid_frame(self, handled: bool = True) -> tuple[bytes, object]:
        cls = self.rng.choice(self.handled if handled else self.others)
        msg = self.message(cls)
        v1 = cls.id < 256 and self.rng.random() < (0.1 if handled else 0.3)
        return self.pack(msg, mavlink1=v1), cls

    # --- datagrams -------------------------------------------------------------------------------------
    def datagram(self) -> tuple[str, bytes]:
        """(kind, bytes) of one datagram."""
        kind = self.rng.choices(self.kind_names, self.kind_weights)[0]
        return kind, getattr(self, f"_{kind}")()

    def _valid(self) -> bytes:
        return self.valid_frame(True)[0]

    def _other(self) -> bytes:
        return self.valid_frame(False)[0]

    def _bad_crc(self) -> bytes:
        frame = bytearray(self.valid_frame(self.rng.random() < 0.8)[0])
        header = V2_HEADER if frame[0] == M.PROTOCOL_MARKER_V2 else M.HEADER_LEN_V1
        pos = self.rng.randrange(header, len(frame))  # payload or checksum: the length stays right
        frame[pos] ^= 1 << self.rng.randrange(8)
        return bytes(frame)

    def _truncated(self) -> bytes:
        frame = self.valid_frame(self.rng.random() < 0.8)[0]
        return frame[: self.rng.randrange(1, len(frame))]

    def _oversized(self) -> bytes:
        frame, cls = self.valid_frame(True)
        if frame[0] != M.PROTOCOL_MARKER_V2:
            return frame + self.rng.randbytes(self.rng.randint(1, 300))  # trailing junk after a v1 frame
        payload = frame[V2_HEADER:-2]
        extra = self.rng.randbytes(self.rng.randint(1, 255 - len(payload))) if len(payload) < 255 else b""
        body = bytearray(frame[:V2_HEADER]) + payload + extra
        body[1] = len(payload) + len(extra)
        crc = crc_of(bytes(body), cls.crc_extra) if self.rng.random() < 0.5 else self.rng.randrange(65536)
        return bytes(body) + struct.pack("<H", crc)

    def _unknown_id(self) -> bytes:
        frame = bytearray(self.valid_frame(True)[0])
        if frame[0] != M.PROTOCOL_MARKER_V2:
            return bytes(frame)  # a v1 frame keeps its id; counted as what it is
        msg_id = self.rng.choice(UNKNOWN_IDS)
        frame[7:10] = msg_id.to_bytes(3, "little")
        return bytes(frame)

    def _bitflip(self) -> bytes:
        frame = bytearray(self.valid_frame(self.rng.random() < 0.8)[0])
        for _ in range(self.rng.randint(1, 4)):
            frame[self.rng.randrange(len(frame))] ^= 1 << self.rng.randrange(8)
        return bytes(frame)

    def _garbage(self) -> bytes:
        return self.rng.randbytes(self.rng.randint(1, 600))


def _as_f32(v: float) -> float:
    """``v`` rounded to float32 (what the wire carries); out-of-range values become infinities."""
    if math.isfinite(v) and abs(v) > 3.4028234663852886e38:
        return math.copysign(math.inf, v)
    return struct.unpack("<f", struct.pack("<f", v))[0]


# --- the oracle ------------------------------------------------------------------------------------------

def parse_datagram(data: bytes) -> tuple[list, int]:
    """(messages, bytes left unparsed) of one datagram through a fresh pymavlink parser."""
    mav = M.MAVLink(None)
    mav.robust_parsing = True
    msgs = mav.parse_buffer(data) or []
    return msgs, mav.buf_len()


def expected_counts(data: bytes, sysid: int = 1, compid: int = 1, handled=HANDLED_TYPES) -> Counter:
    """What the rig counts for one datagram (keys as LinkCounters names them: ``received``, drop
    reasons, ``rx_bytes``, ``bad_bytes``; ``dispatched`` for messages that reach a handler)."""
    out = Counter(rx_bytes=len(data))
    msgs, left = parse_datagram(data)
    if left:
        out["truncated"] += 1
        out["bad_bytes"] += left
    _classify(msgs, sysid, compid, handled, out)
    return out


class StreamOracle:
    """What the rig counts for a byte stream (one TCP connection): frames may span reads. A read
    that ends inside a run of garbage splits the run, so the rig's ``bad_prefix`` count depends
    on how TCP cut the stream: the oracle parses the whole stream at once, which gives the
    fewest runs (a lower bound); every other count and ``bad_bytes`` do not depend on the cuts."""

    CHUNK_DEPENDENT = ("bad_prefix",)

    def __init__(self, sysid: int = 1, compid: int = 1, handled=HANDLED_TYPES):
        self.ids = (sysid, compid, handled)
        self.stream = bytearray()

    def feed(self, data: bytes) -> None:
        self.stream += data

    def counts(self) -> tuple[Counter, int]:
        """(counts, bytes of an incomplete frame at the end, which neither side counts as dropped)."""
        mav = M.MAVLink(None)
        mav.robust_parsing = True
        out = Counter(rx_bytes=len(self.stream))
        _classify(mav.parse_buffer(bytes(self.stream)) or [], *self.ids, out)
        return out, mav.buf_len()


def _classify(msgs, sysid: int, compid: int, handled, out: Counter) -> None:
    for msg in msgs:
        kind = msg.get_type()
        if kind == "BAD_DATA":
            reason = getattr(msg, "reason", "")
            key = "bad_crc" if "CRC" in reason else "bad_prefix" if reason == "Bad prefix" else "bad_data"
            out[key] += 1
            out["bad_bytes"] += len(msg.data)
            continue
        if kind.startswith("UNKNOWN"):
            out["unknown_id"] += 1
            continue
        out["received"] += 1
        if msg.get_srcSystem() == sysid and msg.get_srcComponent() == compid:
            out["own_echo"] += 1
        elif getattr(msg, "target_system", 0) not in (0, sysid):
            out["other_system"] += 1
        elif getattr(msg, "target_component", 0) not in (0, compid):
            out["other_component"] += 1
        elif kind not in handled:
            out["unhandled"] += 1
        else:
            out["dispatched"] += 1
