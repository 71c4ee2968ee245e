"""One ground-station peer: its MAVLink parser and encoder, stream schedule and counters.

Every peer gets its own :class:`protocol.dialect.mavlink.MAVLink` object, so each sees an
unbroken sequence number and a parser state that another peer's bytes cannot corrupt.
pymavlink's generated dialect module does all encoding and decoding.
"""

from __future__ import annotations

import math

from protocol.dialect import mavlink
from rig_emulator.link.endpoints.counters import LinkCounters
from rig_emulator.link.telemetry.streams import StreamSchedule


FLT_MAX = 3.4028234663852886e38


def reset_parse_state(mav) -> None:
    """Forget the bytes a pymavlink parser holds (signing state and sequence numbers stay)."""
    mav.buf = bytearray()
    mav.buf_index = 0
    mav.expected_length = mavlink.HEADER_LEN_V1 + 2
    mav.have_prefix_error = False


def saturate_floats(msg):
    """``msg`` with every finite float field beyond the float32 range replaced by +-inf."""

    def sat(v):
        return math.copysign(math.inf, v) if isinstance(v, float) and math.isfinite(v) and abs(v) > FLT_MAX else v

    for name in msg.get_fieldnames():
        value = getattr(msg, name)
        setattr(msg, name, [sat(v) for v in value] if isinstance(value, list) else sat(value))
    return msg


class Channel:
    """A peer of an endpoint (a TCP client, a UDP address)."""

    def __init__(self, endpoint, key, sysid: int, compid: int, counters: LinkCounters, schedule: StreamSchedule,
                 signing=None):
        self.endpoint = endpoint
        self.key = key
        self.counters = counters
        self.schedule = schedule
        self.signing = signing  # rig_emulator.link.signing.policy.LinkSigning, or None: no signing
        if signing is not None:
            self.mav = signing.parser(sysid, compid)
        else:
            self.mav = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=compid)
            self.mav.robust_parsing = True

    @property
    def name(self) -> str:
        host, port = self.key
        return f"{self.endpoint.kind}:{host}:{port}"

    def receive(self, data: bytes) -> list:
        """Parse incoming bytes; returns the good messages and counts the bad ones.

        A datagram endpoint's read is parsed on its own: bytes of a frame left incomplete at
        the end of a datagram are dropped (``truncated``) instead of swallowing the start of
        the next datagram."""
        self.counters.rx_bytes += len(data)
        self.counters.rx_reads += 1
        try:
            msgs = self.mav.parse_buffer(data) or []
        except Exception:  # noqa: BLE001 - hostile bytes must never stop the rig; the parser resets
            self.mav = self._fresh_parser()
            self.counters.drop("bad_data")
            return []
        if self.endpoint.datagram and self.mav.buf_len():
            self.counters.drop("truncated")
            self.counters.bad_bytes += self.mav.buf_len()
            reset_parse_state(self.mav)
        good = []
        for msg in msgs:
            kind = msg.get_type()
            if kind == "BAD_DATA":
                self.counters.bad_bytes += len(msg.data)
                reason = getattr(msg, "reason", "")
                if "CRC" in reason:
                    self.counters.bad_crc += 1
                    self.counters.drop("bad_crc")
                elif reason == "Invalid signature" and self.signing is not None:
                    self.signing.reject(self)  # counted by reason: unsigned, bad_signature, replay, ...
                elif reason == "Bad prefix":
                    self.counters.drop("bad_prefix")
                else:
                    self.counters.drop("bad_data")
                continue
            if kind.startswith("UNKNOWN"):
                self.counters.drop("unknown_id")
                continue
            self.counters.received += 1
            good.append(msg)
        return good

    def _fresh_parser(self):
        if self.signing is not None:
            mav = self.signing.parser(self.mav.srcSystem, self.mav.srcComponent, link_id=self.mav.signing.link_id)
        else:
            mav = mavlink.MAVLink(None, srcSystem=self.mav.srcSystem, srcComponent=self.mav.srcComponent)
            mav.robust_parsing = True
        mav.seq = self.mav.seq
        return mav

    def send(self, msg) -> None:
        """Encode ``msg`` with this peer's sequence number (and signature) and hand it to the endpoint."""
        mav = self.mav
        if self.signing is not None:
            self.signing.stamp(mav)
        try:
            buf = msg.pack(mav)
        except OverflowError:  # a finite value beyond float32 (a diverged simulation): sent as +-inf
            buf = saturate_floats(msg).pack(mav)
        mav.seq = (mav.seq + 1) % 256
        if self.endpoint.send(self.key, buf if type(buf) is bytes else bytes(buf)):
            self.counters.sent += 1
        else:
            self.counters.drop("tx_overflow")
