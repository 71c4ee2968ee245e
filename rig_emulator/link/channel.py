"""One ground-station peer: its MAVLink parser and encoder, stream schedule and counters.

Every peer gets its own :class:`protocol.dialect.mavlink.MAVLink` object, so each sees an
unbroken sequence number and a parser state that another peer's bytes cannot corrupt.
pymavlink's generated dialect module does all encoding and decoding.
"""

from __future__ import annotations

from protocol.dialect import mavlink
from rig_emulator.link.counters import LinkCounters
from rig_emulator.link.streams import StreamSchedule


class Channel:
    """A peer of an endpoint (a TCP client, a UDP address)."""

    def __init__(self, endpoint, key, sysid: int, compid: int, counters: LinkCounters, schedule: StreamSchedule):
        self.endpoint = endpoint
        self.key = key
        self.counters = counters
        self.schedule = schedule
        self.mav = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self.mav.robust_parsing = True
        self.last_command = None  # (command, params, result) for retried COMMAND_LONGs

    @property
    def name(self) -> str:
        host, port = self.key
        return f"{self.endpoint.kind}:{host}:{port}"

    def receive(self, data: bytes) -> list:
        """Parse incoming bytes; returns the good messages and counts the bad ones."""
        try:
            msgs = self.mav.parse_buffer(data) or []
        except Exception:  # noqa: BLE001 - hostile bytes must never stop the rig; the parser resets
            self.mav = self._fresh_parser()
            self.counters.drop("bad_data")
            return []
        good = []
        for msg in msgs:
            kind = msg.get_type()
            if kind == "BAD_DATA":
                reason = getattr(msg, "reason", "")
                if "CRC" in reason:
                    self.counters.bad_crc += 1
                    self.counters.drop("bad_crc")
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
        mav = mavlink.MAVLink(None, srcSystem=self.mav.srcSystem, srcComponent=self.mav.srcComponent)
        mav.robust_parsing = True
        mav.seq = self.mav.seq
        return mav

    def send(self, msg) -> None:
        """Encode ``msg`` with this peer's sequence number and hand it to the endpoint."""
        buf = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        if self.endpoint.send(self.key, bytes(buf)):
            self.counters.sent += 1
        else:
            self.counters.drop("tx_overflow")
