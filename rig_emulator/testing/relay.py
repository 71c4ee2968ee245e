"""A lossy, laggy UDP relay between a ground station and a rig, for tests and scripts.

::

    client (udpout:127.0.0.1:relay.port)  <->  LossyRelay  <->  rig udpin endpoint

Every datagram, in each direction, is independently dropped with probability ``drop``;
otherwise it is delivered after ``delay_s`` plus a uniform ``jitter_s`` (jitter re-orders
datagrams that follow each other closely), duplicated with probability ``duplicate`` (the copy
with its own delay), and with probability ``reorder`` held back until the next datagram of
that direction has gone out. The settings are attributes and may change while the relay runs
(``relay.drop = 1.0`` cuts the link). A seeded generator makes a run's decisions repeatable
for the same traffic. ``counts`` tells what happened (passed, dropped, duplicated, reordered).
The relay learns the client's address from the client's first datagram.
"""

from __future__ import annotations

import heapq
import random
import select
import socket
import threading
import time


class LossyRelay:
    def __init__(self, rig_addr, drop: float = 0.0, duplicate: float = 0.0, reorder: float = 0.0,
                 delay_s: float = 0.0, jitter_s: float = 0.0, seed: int = 5):
        self.rng = random.Random(seed)
        self.drop, self.duplicate, self.reorder = drop, duplicate, reorder
        self.delay_s, self.jitter_s = delay_s, jitter_s
        self.front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.front.bind(("127.0.0.1", 0))
        self.back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.back.bind(("127.0.0.1", 0))
        self.rig_addr = (rig_addr[0], int(rig_addr[1]))
        self.client_addr = None
        self.counts = {"passed": 0, "dropped": 0, "duplicated": 0, "reordered": 0}
        self._held = {"up": None, "down": None}
        self._queue: list = []  # (due, n, direction, data)
        self._n = 0
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    @classmethod
    def to_rig(cls, rig_urls, **impairments) -> "LossyRelay":
        """A relay in front of the rig's first ``udpin`` endpoint (a URL list as RigThread/RigProcess give)."""
        host, port = next(u for u in rig_urls if u.startswith("udpin:")).split(":")[1:]
        return cls((host, int(port)), **impairments)

    @property
    def port(self) -> int:
        return self.front.getsockname()[1]

    @property
    def client_url(self) -> str:
        """The mavutil connection string a client uses to talk through the relay."""
        return f"udpout:127.0.0.1:{self.port}"

    def _schedule(self, direction: str, data: bytes, now: float) -> None:
        due = now + self.delay_s + (self.rng.uniform(0.0, self.jitter_s) if self.jitter_s > 0 else 0.0)
        self._n += 1
        heapq.heappush(self._queue, (due, self._n, direction, data))

    def _forward(self, direction: str, data: bytes, now: float) -> None:
        r = self.rng.random()
        if r < self.drop:
            self.counts["dropped"] += 1
            return
        if self.rng.random() < self.reorder and self._held[direction] is None:
            self._held[direction] = data  # goes out after the next datagram of this direction
            self.counts["reordered"] += 1
            return
        self._schedule(direction, data, now)
        self.counts["passed"] += 1
        if self.rng.random() < self.duplicate:
            self._schedule(direction, data, now)
            self.counts["duplicated"] += 1
        held, self._held[direction] = self._held[direction], None
        if held is not None:
            self._schedule(direction, held, now)

    def _send_due(self, now: float) -> None:
        while self._queue and self._queue[0][0] <= now:
            _, _, direction, data = heapq.heappop(self._queue)
            try:
                if direction == "up":
                    self.back.sendto(data, self.rig_addr)
                elif self.client_addr is not None:
                    self.front.sendto(data, self.client_addr)
            except OSError:
                pass  # the other side is gone: a datagram lost like any other

    def _run(self) -> None:
        while not self._stop:
            now = time.monotonic()
            self._send_due(now)
            wait = 0.05 if not self._queue else min(max(self._queue[0][0] - now, 0.0), 0.05)
            ready, _, _ = select.select([self.front, self.back], [], [], wait)
            now = time.monotonic()
            for sock in ready:
                try:
                    data, addr = sock.recvfrom(65536)
                except OSError:
                    continue
                if sock is self.front:
                    self.client_addr = addr
                    self._forward("up", data, now)
                else:
                    self._forward("down", data, now)

    def close(self) -> None:
        self._stop = True
        self._thread.join(5)
        self.front.close()
        self.back.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
