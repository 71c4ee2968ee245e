"""MAVLink 2 message signing on every link of the rig (``serve --signing-key``).

pymavlink's own signing does the work: each channel's parser is a
:class:`protocol.dialect.mavlink.MAVLink` with ``signing.secret_key``, ``link_id``,
``sign_outgoing`` and an ``allow_unsigned_callback``, so every message the rig sends is
signed and every message it receives is checked before it is decoded. What this module
adds, as a vehicle needs it:

* **One replay table for all links.** pymavlink keeps the last timestamp of each stream
  ``(link id, system id, component id)`` per parser; the rig's parsers share one table, so a
  packet recorded on one link and replayed on another (a new TCP connection, a new UDP port)
  is rejected like a packet replayed on the same link.
* **A forged packet cannot lock out the real sender.** pymavlink stores a packet's timestamp
  in the stream table *before* it checks the signature, so a packet with a wrong signature
  and a far-future timestamp would make every later genuine packet of that stream look
  replayed. :class:`SigningParser` puts the table back when the signature is wrong.
* **Why a packet was rejected**, counted in the link counters (``dropped``) under
  ``unsigned`` (no signature, or MAVLink 1), ``bad_signature`` (another key, or altered),
  ``replay`` (timestamp not newer than the last accepted one of its stream: a replayed or
  reordered packet) and ``stale_timestamp`` (the first packet of a stream more than a
  minute older than the rig's clock, pymavlink's rule for new streams). Every
  :data:`REPORT_EVERY_S` seconds with new rejections the rig sends a STATUSTEXT to each link
  that sent them and logs a line with the totals.
* **The timestamp** comes from one :class:`~rig_emulator.link.signing.clock.SigningClock`
  for every link; it and the recent stream table are stored in the state directory every
  :data:`~rig_emulator.link.signing.clock.SAVE_EVERY_S` seconds and at shutdown, so a
  restarted rig neither goes back in time nor accepts a replay of what it accepted before a
  clean stop. (After a SIGKILL, what the last seconds before it accepted can be replayed once
  within the following minute.)

Policy with a key: everything must be signed with it, reads included (PARAM_REQUEST_LIST,
MISSION_REQUEST_LIST, ...), except RADIO_STATUS (the spec's example, ArduPilot's rule), which
the rig accepts unsigned and does not act on. Rejected packets get no answer (no
COMMAND_ACK, PARAM_VALUE or MISSION_ACK): an unauthenticated sender learns nothing but the
periodic STATUSTEXT. SETUP_SIGNING is never acted on: the key is set on the command line.
"""

from __future__ import annotations

import time
from collections import Counter, deque

from protocol.dialect import mavlink as M
from rig_emulator.link.signing.clock import SAVE_EVERY_S, SigningClock

UNSIGNED_ALLOWED = frozenset({M.MAVLINK_MSG_ID_RADIO_STATUS})
REASONS = ("unsigned", "bad_signature", "replay", "stale_timestamp")
REASON_TEXT = {"unsigned": "unsigned", "bad_signature": "wrongly signed", "replay": "replayed",
               "stale_timestamp": "stale"}
NEW_STREAM_WINDOW = 6000 * 1000  # pymavlink: a new stream may start at most one minute behind the clock
REPORT_EVERY_S = 5.0


def message_name(msg_id: int | None) -> str:
    if msg_id is None:
        return "?"
    cls = M.mavlink_map.get(msg_id)
    return cls.msgname if cls is not None else f"id {msg_id}"


class SigningParser(M.MAVLink):
    """A channel's pymavlink parser/encoder with signing on (see the module doc)."""

    def __init__(self, owner: "LinkSigning", link_id: int, src_system: int, src_component: int):
        super().__init__(None, srcSystem=src_system, srcComponent=src_component)
        self.robust_parsing = True
        self.owner = owner
        s = self.signing
        s.secret_key = owner.key
        s.link_id = link_id
        s.sign_outgoing = True
        s.timestamp = owner.clock.current()
        s.stream_timestamps = owner.streams  # one table for every link
        s.allow_unsigned_callback = self._allow_unsigned
        self.rejections: deque = deque()  # (reason, msg id), one per "Invalid signature" BAD_DATA
        self._failure: str | None = None

    def check_signature(self, msgbuf, srcSystem, srcComponent) -> bool:
        link_id = msgbuf[-13]
        stamp = int.from_bytes(bytes(msgbuf[-12:-6]), "little")
        key = (link_id, srcSystem, srcComponent)
        streams = self.signing.stream_timestamps
        last = streams.get(key)
        self.signing.timestamp = max(self.signing.timestamp, self.owner.clock.current())
        if super().check_signature(msgbuf, srcSystem, srcComponent):
            self.owner.clock.observe(stamp)
            return True
        if last is None:  # pymavlink recorded the stamp before checking the signature: undo
            streams.pop(key, None)
        else:
            streams[key] = last
        if last is not None and stamp <= last:
            self._failure = "replay"
        elif last is None and stamp + NEW_STREAM_WINDOW < self.signing.timestamp:
            self._failure = "stale_timestamp"
        else:
            self._failure = "bad_signature"
        return False

    def _allow_unsigned(self, mav, msg_id: int) -> bool:
        reason, self._failure = self._failure or "unsigned", None
        if reason == "unsigned" and msg_id in UNSIGNED_ALLOWED:
            return True
        self.rejections.append((reason, msg_id))
        return False


class LinkSigning:
    """The signing state shared by every channel of a server.

    ``stored`` is ``(timestamp, streams)`` as :meth:`snapshot` returned it before the last
    stop; ``save(snapshot)`` stores one (errors are logged, never fatal); ``log(text)``
    prints a line for the operator.
    """

    def __init__(self, key: bytes, stored: tuple | None = None, save=None, log=None):
        if len(key) != 32:
            raise ValueError("a MAVLink signing key is 32 bytes")
        self.key = bytes(key)
        timestamp, streams = stored if stored is not None else (0, {})
        self.clock = SigningClock(timestamp)
        self.streams: dict = dict(streams)
        self.save = save
        self.log = log
        self.rejected: Counter = Counter()
        self._pending: dict = {}  # channel -> [Counter of reasons, last msg id]
        self._server = None
        self._next_link_id = 0
        self._next_report = 0.0
        self._next_save = time.monotonic() + SAVE_EVERY_S

    def bind(self, server) -> None:
        """The server whose channels and STATUSTEXT this signing uses."""
        self._server = server

    # --- channels ---------------------------------------------------------------------------------
    def parser(self, src_system: int, src_component: int, link_id: int | None = None) -> SigningParser:
        """A parser/encoder for a channel: a new one gets the next link id (0..255, wrapping)."""
        if link_id is None:
            link_id = self._next_link_id
            self._next_link_id = (self._next_link_id + 1) % 256
        return SigningParser(self, link_id, src_system, src_component)

    def stamp(self, mav) -> None:
        """Before packing a message on ``mav``: the next timestamp of the shared clock."""
        mav.signing.timestamp = self.clock.next()

    def reject(self, channel) -> None:
        """Count the oldest unreported rejection of ``channel``'s parser."""
        rejections = getattr(channel.mav, "rejections", None)
        reason, msg_id = rejections.popleft() if rejections else ("bad_signature", None)
        channel.counters.drop(reason)
        self.rejected[reason] += 1
        pending = self._pending.setdefault(channel, [Counter(), None])
        pending[0][reason] += 1
        pending[1] = msg_id

    # --- periodic work ----------------------------------------------------------------------------
    def tick(self, now: float) -> None:
        """Report new rejections (at most every REPORT_EVERY_S) and store the clock when due."""
        if self._pending and now >= self._next_report:
            self._report()
            self._next_report = now + REPORT_EVERY_S
        if self.save is not None and now >= self._next_save:
            self._next_save = now + SAVE_EVERY_S
            self.store()

    def _report(self) -> None:
        pending, self._pending = self._pending, {}
        live = set(map(id, self._server.channels.values())) if self._server is not None else set()
        last_text = ""
        for channel, (counts, msg_id) in pending.items():
            parts = ", ".join(f"{n} {REASON_TEXT[r]}" for r, n in sorted(counts.items()))
            last_text = f"last {message_name(msg_id)} from {channel.name}"
            if id(channel) in live:
                self._server.statustext(channel, M.MAV_SEVERITY_WARNING,
                                        f"signing: rejected {parts} packets (last {message_name(msg_id)}); "
                                        f"this rig needs MAVLink 2 signing with its key")
        if self.log is not None:
            totals = ", ".join(f"{r} {self.rejected[r]}" for r in REASONS if self.rejected[r])
            self.log(f"signing: rejected packets so far: {totals} ({last_text})")

    def snapshot(self) -> tuple:
        """(timestamp, streams) worth storing: streams a replay could still pass are the recent ones."""
        now = self.clock.current()
        recent = {k: v for k, v in self.streams.items() if v + NEW_STREAM_WINDOW >= now}
        return now, recent

    def store(self) -> None:
        if self.save is None:
            return
        try:
            self.save(self.snapshot())
        except (OSError, ValueError) as exc:
            if self.log is not None:
                self.log(f"signing: cannot store the signing timestamp: {exc}")

    def close(self) -> None:
        """At shutdown: the final report and the clock stored."""
        if self._pending:
            self._report()
        self.store()


def refuse_setup_signing(server, msg, channel) -> None:
    """SETUP_SIGNING is not acted on; say why (the key comes from the command line)."""
    server.counters.drop("setup_signing")
    server.statustext(channel, M.MAV_SEVERITY_WARNING,
                      "SETUP_SIGNING ignored: the rig's key is set with rig-emulator --signing-key")
