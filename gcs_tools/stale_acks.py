"""Telling a command's COMMAND_ACK from stale ones on a link that duplicates, delays or re-orders.

COMMAND_ACK names the command, not the transmission it answers, so on a bad link an ACK of the
*previous* command with the same id can arrive while the next one is awaited, and be taken for
its answer: if that next command was lost, the ground station would report it done when the
vehicle never saw it. Two sources, two remedies:

* a **duplicated frame** of an ACK already consumed: same sender and MAVLink sequence number;
  :class:`StaleAcks` remembers the frames it consumed for :data:`FRAME_MEMORY_S` and
  :meth:`StaleAcks.fresh` refuses them (sequence numbers wrap after 256 messages, so the memory
  is short; a genuine ACK refused by a coincidence only costs a retry);
* the answer to **another transmission** of a retried command, arriving after the ACK that
  ended the wait: after a command that needed retries, ACKs of that command arriving within the
  timeout after the last transmission are consumed (:meth:`StaleAcks.absorb`), as a round trip
  longer than the timeout is beyond what the client was configured for.
"""

from __future__ import annotations

import time
from collections import deque

FRAME_MEMORY_S = 1.0


class StaleAcks:
    def __init__(self):
        self._frames: deque = deque()  # (time consumed, (sysid, compid, seq))

    def _forget_old(self, now: float) -> None:
        while self._frames and now - self._frames[0][0] > FRAME_MEMORY_S:
            self._frames.popleft()

    @staticmethod
    def _key(msg) -> tuple:
        return msg.get_srcSystem(), msg.get_srcComponent(), msg.get_seq()

    def fresh(self, msg) -> bool:
        """False for a frame identical (sender, sequence number) to one consumed moments ago."""
        now = time.monotonic()
        self._forget_old(now)
        return all(key != self._key(msg) for _, key in self._frames)

    def consumed(self, msg) -> None:
        self._frames.append((time.monotonic(), self._key(msg)))

    def absorb(self, link, cmd: int, until: float) -> None:
        """Consume the ACKs of ``cmd`` that arrive before ``until`` (monotonic seconds)."""
        while True:
            left = until - time.monotonic()
            if left <= 0:
                return
            ack = link.recv("COMMAND_ACK", left, lambda m: m.command == cmd)
            if ack is None:
                return
            self.consumed(ack)
