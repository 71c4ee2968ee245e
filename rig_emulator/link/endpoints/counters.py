"""Counters of what a link received, handled and dropped (readable by tests and tools)."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field


@dataclass
class LinkCounters:
    """Totals over every channel of a server.

    ``dropped`` counts messages (or byte runs) that were not acted on, keyed by reason:
    ``bad_data`` (garbage, truncated frames, bad CRCs as reported by the parser),
    ``other_system`` / ``other_component`` (addressed elsewhere), ``unhandled`` (a message
    the rig does not act on), ``invalid`` (a handled message with unusable fields, e.g.
    NaN set-points), ``peer_limit`` (a UDP peer beyond the endpoint's limit),
    ``tx_overflow`` (an outgoing message dropped because a client does not read),
    ``truncated`` (a UDP datagram ending inside a frame: a frame never spans datagrams),
    ``duplicate_command`` (a retried or duplicated COMMAND_LONG answered without acting again);
    with ``--signing-key`` (:mod:`rig_emulator.link.signing.policy`): ``unsigned``, ``bad_signature``,
    ``replay`` and ``stale_timestamp`` (packets rejected before decoding), ``setup_signing``.

    Bytes: ``rx_bytes`` read from every peer in ``rx_reads`` reads (datagrams, TCP reads),
    ``bad_bytes`` of them in garbage, bad frames and truncated datagrams. The loop:
    ``steps`` physics steps run, ``pacing_resets`` times the pacing gave up catching up with
    wall-clock time (more than ``MAX_LAG_S`` x speed-up behind) and ``lag_dropped_s``, the
    simulated seconds of lag it gave up then. :mod:`rig_emulator.link.telemetry.link_status` sends all
    of them to a client on request.
    """

    received: int = 0
    bad_crc: int = 0
    sent: int = 0
    commands: int = 0
    dropped: Counter = field(default_factory=Counter)
    rx_bytes: int = 0
    rx_reads: int = 0
    bad_bytes: int = 0
    steps: int = 0
    pacing_resets: int = 0
    lag_dropped_s: float = 0.0

    def drop(self, reason: str, n: int = 1) -> None:
        self.dropped[reason] += n

    def pacing_reset(self, lag_s: float) -> None:
        """The pacing re-anchored ``lag_s`` simulated seconds behind its schedule."""
        self.pacing_resets += 1
        self.lag_dropped_s += lag_s

    def as_dict(self) -> dict:
        return {"received": self.received, "bad_crc": self.bad_crc, "sent": self.sent,
                "commands": self.commands, "dropped": dict(self.dropped), "rx_bytes": self.rx_bytes,
                "rx_reads": self.rx_reads, "bad_bytes": self.bad_bytes, "steps": self.steps,
                "pacing_resets": self.pacing_resets, "lag_dropped_s": self.lag_dropped_s}
