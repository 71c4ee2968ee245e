"""MAVProxy (PyPI, driven through its stdin) against a rig: MAVFTP and component metadata,
the parameter download falling back from FTP, ``fence`` enable/disable and a breach, and
``wp load`` of a file made by ``rig-gcs mission make --rectangle 5x3`` flown to the end.

The rig runs in this process (RigThread at 4x) so the test can read where it flew."""

import json
import time

import numpy as np
import pytest

from gcs_tools.cli import main as rig_gcs
from rig_emulator.link.ftp.component_metadata import parameter_metadata
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.mavproxy import MAVProxySession
from rig_emulator.testing.rig import RigThread

pytestmark = [pytest.mark.slow]


def test_mavproxy_ftp_fence_and_wp_load(tmp_path):
    plan = tmp_path / "rect.waypoints"
    assert rig_gcs(["mission", "make", str(plan), "--rectangle", "5x3", "--altitude", "2"]) == 0
    assert "\t3\t16\t" in plan.read_text()  # GLOBAL_RELATIVE_ALT items: no local x/y for MAVProxy to scale
    with RigThread(speedup=4.0) as rig:
        with MAVProxySession(rig.tcp_url, tmp_path) as mp:
            do = mp.do
            # MAVProxy asks for @PARAM/param.pck over FTP first; the rig NAKs it (not found) and the
            # parameter protocol delivers every parameter
            got = mp.wait_for(r"Received (\d+) parameters", 120)
            assert got is not None and int(got.group(1)) == len(ParamTable()), mp.transcript()
            do("ftp list /metadata", r"parameters\.json\s+(\d+)")
            local = tmp_path / "parameters.json"
            wrote = do(f"ftp get /metadata/parameters.json {local}", r"Wrote (\d+) bytes")
            # MAVProxy prints "Wrote N bytes" before its file buffer is flushed: wait for all N on disk
            deadline = time.monotonic() + 20.0
            while local.stat().st_size < int(wrote.group(1)) and time.monotonic() < deadline:
                time.sleep(0.1)
            assert local.read_bytes() == parameter_metadata()
            entries = {p["name"]: p for p in json.loads(local.read_text())["parameters"]}
            assert [v["description"] for v in entries["CTL_STRATEGY"]["values"]] == ["smc-flc", "flc", "smc", "pid"]
            do("ftp put x.txt /x.txt", None)
            # fence on/off (MAV_CMD_DO_FENCE_ENABLE) as MAVProxy reports it from SYS_STATUS
            do("fence disable", r"fence disabled")
            do("fence enable", r"fence enabled")
            # the rectangle, loaded by MAVProxy, flown by the rig
            do(f"wp load {plan}", r"Sent all 6 waypoints")
            do("arm throttle", None)
            do("long MISSION_START 0 0", None)
            deadline = time.monotonic() + 240
            while not rig.server.rig.mission_status().done and time.monotonic() < deadline:
                time.sleep(0.5)
            status = rig.server.rig.mission_status()
            assert status.done and np.all(np.isfinite(status.reached_t)), status
            wps = rig.server.mission.plan.waypoints
            assert np.allclose(wps[1:], [[0, 0, 2], [5, 0, 2], [5, 3, 2], [0, 3, 2], [0, 0, 2]], atol=0.05), wps
            # a fence breach: FENCE_ALT_MAX below the hover height -> hold, reported
            do("param set FENCE_ALT_MAX 1", r"fence breach")
            transcript = mp.transcript()
            assert "above the fence maximum 1 m" in mp.transcript() or mp.wait_for(r"fence maximum 1 m", 10)
        assert "Traceback" not in mp.before_exit, mp.before_exit
        assert transcript
