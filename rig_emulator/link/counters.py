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
    ``tx_overflow`` (an outgoing message dropped because a client does not read).
    """

    received: int = 0
    bad_crc: int = 0
    sent: int = 0
    commands: int = 0
    dropped: Counter = field(default_factory=Counter)

    def drop(self, reason: str, n: int = 1) -> None:
        self.dropped[reason] += n

    def as_dict(self) -> dict:
        return {"received": self.received, "bad_crc": self.bad_crc, "sent": self.sent,
                "commands": self.commands, "dropped": dict(self.dropped)}
