"""``rig-emulator serve --instance N``: three rigs side by side on the offsets of ArduPilot's
``-I N`` (system id N + 1, TCP 5760 + 10 N, UDP out 14550 + 10 N, state rig-state-N), flown
from one pymavlink process, each with its own mission. High instance numbers keep the ports
clear of rigs other tests start with the default endpoints."""

import os
import signal
import subprocess
import sys

import pytest

from rig_emulator.testing.rig import TEST_AIRFRAME
from pymavlink import mavutil

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionItem
from rig_emulator.link.serve_args import instance_endpoints, instance_state_dir, instance_sysid
from protocol.dialect import use_hilms_dialect
from rig_emulator.testing.rig import MissionClient, command, recv

pytestmark = [pytest.mark.slow]
INSTANCES = (41, 42, 43)
ENU = M.MAV_FRAME_LOCAL_ENU


def test_instance_offsets():
    assert instance_endpoints(0) == ["udpout:127.0.0.1:14550", "tcpin:127.0.0.1:5760"]
    assert instance_endpoints(3) == ["udpout:127.0.0.1:14580", "tcpin:127.0.0.1:5790"]
    assert (instance_sysid(0), instance_sysid(3)) == (1, 4)
    assert (instance_state_dir(0), instance_state_dir(3)) == ("rig-state", "rig-state-3")


def test_three_rigs_fly_their_own_missions_from_one_process(tmp_path):
    use_hilms_dialect()
    procs, conns = [], {}
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    try:
        for n in INSTANCES:
            procs.append(subprocess.Popen(
                [sys.executable, "-m", "rig_emulator", "serve", "--instance", str(n), "--speedup", "8",
                 "--airframe", TEST_AIRFRAME],
                cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env))
        for n, proc in zip(INSTANCES, procs):
            lines = [proc.stdout.readline() for _ in range(3)]
            tcp = instance_endpoints(n)[1]
            assert any(f"serving {tcp}" in ln for ln in lines), lines
            conns[n] = mavutil.mavlink_connection(f"tcp:127.0.0.1:{tcp.rsplit(':', 1)[1]}", source_system=255,
                                                  autoreconnect=False)
        for n, conn in conns.items():
            hb = recv(conn, "HEARTBEAT", 20)
            assert hb.get_srcSystem() == n + 1 and hb.autopilot == M.MAV_AUTOPILOT_PX4
            assert (tmp_path / f"rig-state-{n}").is_dir()
            # each rig its own mission: a take-off to 1 m, then a waypoint n - 40 metres east
            items = [MissionItem(0, ENU, M.MAV_CMD_NAV_TAKEOFF, z=1.0, current=1),
                     MissionItem(1, ENU, M.MAV_CMD_NAV_WAYPOINT, x=float(n - 40), z=1.0)]
            client = MissionClient(conn, target=(n + 1, 1))
            assert client.upload(items) == M.MAV_MISSION_ACCEPTED
            assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1, target=(n + 1, 1)).result == M.MAV_RESULT_ACCEPTED
            assert command(conn, M.MAV_CMD_MISSION_START, 0, 0, target=(n + 1, 1)).result == M.MAV_RESULT_ACCEPTED
        for n, conn in conns.items():
            assert recv(conn, "MISSION_ITEM_REACHED", 60, lambda m: m.seq == 1) is not None, n
            pos = recv(conn, "LOCAL_POSITION_NED", 5)
            assert abs(pos.y - (n - 40)) < 0.15 and abs(pos.x) < 0.15, (n, pos)
    finally:
        for conn in conns.values():
            conn.close()
        for proc in procs:
            proc.send_signal(signal.SIGTERM)
        for proc in procs:
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
