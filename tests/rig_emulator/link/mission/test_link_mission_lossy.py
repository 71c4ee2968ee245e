"""A lossy link: a UDP relay (rig_emulator.testing.relay) between a pymavlink client and the
rig drops 20 % of the datagrams each way, duplicates 10 % and holds back 10 % until after the
next one (reordering). A 100-item upload and download still complete and match exactly: the
rig re-requests missing items, the client (:class:`rig_emulator.testing.rig.MissionClient`) resends per
the protocol's retry rules, duplicates and stale replies are ignored on both sides."""

import time

from protocol.dialect import mavlink as M
from protocol.mission_items import waypoint_items
from rig_emulator.testing.rig import MissionClient, RigThread, connect, recv
from rig_emulator.testing.relay import LossyRelay

DROP, DUPLICATE, HOLD = 0.20, 0.10, 0.10


def test_100_items_up_and_down_over_a_lossy_link():
    with RigThread(speedup=1.0, extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        relay = LossyRelay.to_rig(rig.urls, drop=DROP, duplicate=DUPLICATE, reorder=HOLD)
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
