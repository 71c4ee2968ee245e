"""QGC WPL 110 files through pymavlink's ``mavwp`` loader and MAVProxy's ``wp load`` / ``wp list``.

MAVProxy uploads line 0 of the file (ArduPilot's home line) as item 0; under the rig's
default (PX4) convention it is a waypoint at home, flown like the others; MAVProxy's
``param set MIS_ITEM0_HOME 1`` switches the rig to ArduPilot's convention (its effect on
uploads is covered in test_link_mission_protocol.py). MAVProxy is driven through its stdin and
judged by its output (rig_emulator.testing.mavproxy)."""

import numpy as np
import pytest
from pymavlink import mavwp

from protocol.dialect import mavlink as M
from protocol.mission_items import item_from_message
from rig_emulator.testing.mavproxy import MAVProxySession
from rig_emulator.testing.rig import RigProcess, RigThread, connect, recv

pytestmark = [pytest.mark.slow]

WPL = """QGC WPL 110
0\t1\t0\t16\t0\t0\t0\t0\t35.700000\t51.400000\t1200.000000\t1
1\t0\t3\t22\t0\t0\t0\t0\t0\t0\t2.000000\t1
2\t0\t3\t16\t0\t0\t0\t0\t35.700020\t51.400000\t2.000000\t1
3\t0\t3\t178\t1\t1.5\t-1\t0\t0\t0\t0\t1
4\t0\t3\t16\t2\t0.1\t0\t0\t35.700020\t51.400030\t2.000000\t1
5\t0\t3\t21\t0\t0\t0\t0\t0\t0\t0\t1
"""


def _send_loader(conn, loader):
    """Upload a MAVWPLoader's MISSION_ITEMs the way a pymavlink script does."""
    conn.mav.mission_count_send(1, 1, loader.count(), 0)
    while True:
        m = recv(conn, ["MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"], 5)
        assert m is not None
        if m.get_type() == "MISSION_ACK":
            return m.type
        w = loader.wp(m.seq)
        w.target_system, w.target_component = 1, 1
        conn.mav.send(w)


def test_mavwp_loader_upload_and_download(tmp_path):
    path = tmp_path / "mission.txt"
    path.write_text(WPL)
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(path)) == 6
    with RigThread(speedup=1.0) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert _send_loader(conn, loader) == M.MAV_MISSION_ACCEPTED
        plan = rig.server.mission.plan
        assert plan.seqs == (0, 1, 2, 4, 5)  # PX4 convention: item 0 flown; 3 is DO_CHANGE_SPEED
        # line 0 is home itself (AMSL 1200 m); MISSION_ITEM's float32 latitude is good to ~0.2 m
        assert np.allclose(plan.waypoints[0], [0.0, 0.0, 0.0], atol=0.3)
        assert list(plan.speeds) == [0.0, 0.0, 0.0, 1.5, 1.5] and plan.holds[3] == 2.0 and plan.radii[3] == np.float32(0.1)
        conn.mav.mission_request_list_send(1, 1, 0)
        assert recv(conn, "MISSION_COUNT", 5).count == 6
        for seq in range(6):
            conn.mav.mission_request_send(1, 1, seq, 0)
            m = recv(conn, "MISSION_ITEM", 5, lambda m: m.seq == seq)
            want = loader.wp(seq)
            got = item_from_message(m)
            assert (got.command, got.frame, got.param1, got.param2) == (want.command, want.frame,
                                                                        np.float32(want.param1), np.float32(want.param2))
            assert np.float32(got.x) == np.float32(want.x) and np.float32(got.y) == np.float32(want.y)
        conn.mav.mission_ack_send(1, 1, 0, 0)
        conn.close()


def test_mavproxy_wp_load_and_list(tmp_path):
    path = tmp_path / "mission.txt"
    path.write_text(WPL)
    with RigProcess(speedup=1.0) as rig:
        with MAVProxySession(rig.tcp_url, tmp_path) as mp:
            assert mp.wait_for(r"Received \d+ parameters") is not None, mp.transcript()
            mp.do(f"wp load {path}", r"Sent all 6 waypoints")
            mp.do("wp list", r"Saved 6 waypoints")
            listing = mp.transcript()
            assert "16 3 35.7000200000 51.4000000000 2.000000" in listing, listing
            assert "178 3 " in listing and "21 3 " in listing
            # MAVProxy users switch the rig to ArduPilot's item-0-is-home convention themselves
            mp.send("param set MIS_ITEM0_HOME 1")
            shown = None
            for _ in range(20):  # MAVProxy shows its cache; it changes when the rig's PARAM_VALUE echo arrives
                mp.send("param show MIS_ITEM0_HOME")
                shown = mp.wait_for(r"MIS_ITEM0_HOME\s+1(\.0)?\s*$", 1.0)
                if shown is not None:
                    break
            assert shown is not None, mp.transcript()
        assert "Traceback" not in mp.before_exit and "Exception" not in mp.before_exit, mp.before_exit
        assert rig.stop() == 0
