"""The MAVLink 2 signing timestamp: 10 microsecond units since 2015-01-01 00:00 UTC.

One clock serves every link of the rig, so every signed packet the rig sends, on any link,
carries a timestamp larger than the one before (the spec asks this per link; one clock for
all is stricter and lets a ground station that sees the rig over two links accept both).
:meth:`SigningClock.next` is ``max(last + 1, wall clock)``: it follows the wall clock while
the rig sends fewer than 100 000 packets a second and never goes backwards, even when the
system clock does. The spec's other rules:

* the timestamp is stored in persistent storage at least every minute, and on start the
  clock begins at ``max(stored, wall clock)`` (:mod:`rig_emulator.link.state.rig_state` stores
  it every :data:`SAVE_EVERY_S` and at shutdown);
* a newer timestamp on an accepted incoming packet moves the clock on (:meth:`observe`).
"""

from __future__ import annotations

import time

MAVLINK_EPOCH_UNIX_S = 1420070400  # 2015-01-01T00:00:00Z
TICKS_PER_S = 100_000
MAX_TIMESTAMP = 2**48 - 1
SAVE_EVERY_S = 10.0


def wall_timestamp(unix_s: float | None = None) -> int:
    """The signing timestamp of a Unix time (now by default)."""
    t = time.time() if unix_s is None else unix_s
    return max(int((t - MAVLINK_EPOCH_UNIX_S) * TICKS_PER_S), 0)


class SigningClock:
    def __init__(self, stored: int = 0):
        if not 0 <= stored <= MAX_TIMESTAMP:
            raise ValueError(f"signing timestamp {stored} outside 0..2^48-1")
        self.last = max(int(stored), wall_timestamp())

    def current(self) -> int:
        """The largest timestamp used or seen so far, or the wall clock if later (no tick)."""
        return max(self.last, wall_timestamp())

    def next(self) -> int:
        """The timestamp of the next packet sent (strictly increasing)."""
        self.last = max(self.last + 1, wall_timestamp())
        return self.last

    def observe(self, timestamp: int) -> None:
        """An accepted incoming packet's timestamp: the clock never stays behind it."""
        if timestamp > self.last:
            self.last = min(int(timestamp), MAX_TIMESTAMP)
