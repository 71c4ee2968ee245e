"""A lossy link: a UDP relay between a pymavlink client and the rig drops 20 % of the datagrams
each way, duplicates 10 % and holds back 10 % until after the next one (reordering). A
100-item upload and download still complete and match exactly: the rig re-requests
missing items, the client (:class:`rig_emulator.link.testing.MissionClient`) resends per
the protocol's retry rules, duplicates and stale replies are ignored on both sides."""

import random
import select
import socket
import threading
import time

from protocol.dialect import mavlink as M
from protocol.mission_items import waypoint_items
from rig_emulator.link.testing import MissionClient, RigThread, connect, recv

DROP, DUPLICATE, HOLD = 0.20, 0.10, 0.10


class LossyRelay:
    """Client <-> relay (front socket) <-> rig (back socket), impairing both directions."""

    def __init__(self, rig_addr, seed=5):
        self.rng = random.Random(seed)
        self.front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.front.bind(("127.0.0.1", 0))
        self.back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.back.bind(("127.0.0.1", 0))
        self.rig_addr = rig_addr
        self.client_addr = None
        self.held = {"up": None, "down": None}
        self.counts = {"passed": 0, "dropped": 0, "duplicated": 0, "reordered": 0}
        self._stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    @property
    def port(self) -> int:
        return self.front.getsockname()[1]

    def _send(self, direction, data):
        if direction == "up":
            self.back.sendto(data, self.rig_addr)
        elif self.client_addr is not None:
            self.front.sendto(data, self.client_addr)

    def _forward(self, direction, data):
        r = self.rng.random()
        if r < DROP:
            self.counts["dropped"] += 1
            return
        if r < DROP + HOLD and self.held[direction] is None:
            self.held[direction] = data  # goes out after the next datagram
            self.counts["reordered"] += 1
            return
        self._send(direction, data)
        self.counts["passed"] += 1
        if self.rng.random() < DUPLICATE:
            self._send(direction, data)
            self.counts["duplicated"] += 1
        if self.held[direction] is not None:
            self._send(direction, self.held[direction])
            self.held[direction] = None

    def _run(self):
        while not self._stop:
            ready, _, _ = select.select([self.front, self.back], [], [], 0.05)
            for sock in ready:
                data, addr = sock.recvfrom(65536)
                if sock is self.front:
                    self.client_addr = addr
                    self._forward("up", data)
                else:
                    self._forward("down", data)

    def close(self):
        self._stop = True
        self.thread.join(5)
        self.front.close()
        self.back.close()


def test_100_items_up_and_down_over_a_lossy_link():
    with RigThread(speedup=1.0, extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        host, port = next(u for u in rig.urls if u.startswith("udpin:")).split(":")[1:]
        relay = LossyRelay((host, int(port)))
        conn = connect(f"udpin:127.0.0.1:{relay.port}")
        try:
            for _ in range(50):  # the link is lossy from the first datagram on
                conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
                if recv(conn, "HEARTBEAT", 0.5) is not None:
                    break
            home = rig.server.ctx.home
            items = waypoint_items([[0.05 * i, 0.03 * i, 2.0] for i in range(100)], home)
            client = MissionClient(conn, retry_s=0.25, max_retries=40, window=4)
            t0 = time.monotonic()
            assert client.upload(items) == M.MAV_MISSION_ACCEPTED
            t1 = time.monotonic()
            back = client.download()
            t2 = time.monotonic()
            assert back == items
            assert rig.server.mission.items == tuple(items)
            c = relay.counts
            assert c["dropped"] > 50 and c["duplicated"] > 10 and c["reordered"] > 10, c
            print(f"\nlossy link {c}: upload {t1 - t0:.2f} s, download {t2 - t1:.2f} s, client resends "
                  f"{client.retries}, rig counters {dict(rig.server.counters.dropped)}")
        finally:
            conn.close()
            relay.close()
