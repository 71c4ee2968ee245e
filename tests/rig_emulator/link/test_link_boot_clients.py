"""MAVProxy and MAVSDK-Python connect to a rig that is still starting (on a cold first
start they gave up before its first HEARTBEAT) and work with it once it runs.

The start takes longer than their connection timeouts (15-20 s): the documented seam
``HILMS_SERVE_BOOT_DELAY_S`` stands in for the cold compile (rig_emulator/link/serve.py).
"""

import queue
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.action import Action

from protocol.dialect import mavlink as M
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.rig import RigProcess, connect, recv

MAVPROXY = Path(sys.executable).parent / "mavproxy.py"
pytestmark = [pytest.mark.slow]
SLOW_START = {"HILMS_SERVE_BOOT_DELAY_S": "25"}  # longer than MAVSDK's 20 s and MAVProxy's patience


class _Lines:
    """MAVProxy's output lines, read in a thread; ``wait_for`` a regular expression."""

    def __init__(self, proc):
        self.q, self.all = queue.Queue(), []
        threading.Thread(target=self._pump, args=(proc,), daemon=True).start()

    def _pump(self, proc):
        for line in proc.stdout:
            self.all.append(line)
            self.q.put(line)
        self.q.put(None)

    def wait_for(self, pattern: str, timeout: float):
        while True:
            try:
                line = self.q.get(timeout=timeout)
            except queue.Empty:
                return None
            if line is None:
                return None
            m = re.search(pattern, line)
            if m:
                return m


def test_mavproxy_waits_out_a_slow_start(tmp_path):
    """Over UDP: MAVProxy also parses the rig's packed datagrams (several frames each)."""
    rig = RigProcess(speedup=1.0, extra_endpoints=["udpin:127.0.0.1:0"], wait_ready=False, env=SLOW_START)
    try:
        port = next(u for u in rig.urls if u.startswith("udpin:")).rsplit(":", 1)[1]
        proc = subprocess.Popen(
            # -u: `status` writes to stdout without a flush; piped, it could wait in the buffer past the timeout
            [sys.executable, "-u", str(MAVPROXY), f"--master=udpout:127.0.0.1:{port}", f"--state-basedir={tmp_path}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
        out = _Lines(proc)
        try:
            assert out.wait_for(r"starting: compiling the step loop", timeout=30) is not None, "".join(out.all)
            assert not rig.ready
            got = out.wait_for(r"Received (\d+) parameters", timeout=240)
            assert got is not None, "".join(out.all)
            assert int(got.group(1)) == len(ParamTable())
            assert rig.ready or rig.wait_ready(30) is None
            # `status` lists the messages MAVProxy has received: right after the rig becomes ready the
            # first ATTITUDE may still be on its way, so ask again until it is there
            for _ in range(15):
                proc.stdin.write("status ATTITUDE\n")
                proc.stdin.flush()
                if out.wait_for(r"ATTITUDE \{time_boot_ms : \d+, roll : ", timeout=2) is not None:
                    break
            else:
                raise AssertionError("MAVProxy's `status ATTITUDE` never showed an ATTITUDE\n" + "".join(out.all))
            before_exit = "".join(out.all)
            proc.stdin.write("exit\n")
            proc.stdin.close()
            proc.wait(30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        assert "Traceback" not in before_exit and "Exception" not in before_exit, before_exit
    finally:
        code = rig.stop()
    assert code == 0


def test_mavsdk_finds_a_starting_rig_and_arms_it_once_ready():
    rig = RigProcess(speedup=1.0, extra_endpoints=["udpin:127.0.0.1:0"], wait_ready=False, env=SLOW_START)
    try:
        udp_port = next(u for u in rig.urls if u.startswith("udpin:")).rsplit(":", 1)[1]
        sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        try:
            sdk.add_any_connection(f"udpout://127.0.0.1:{udp_port}")
            system = sdk.first_autopilot(20.0)
            assert system is not None, "MAVSDK found no autopilot within 20 s"
            assert not rig.ready  # found while the rig was starting
            rig.wait_ready(240)
            obs = connect(rig.tcp_url)
            assert recv(obs, "HEARTBEAT", 10, lambda m: m.system_status == M.MAV_STATE_STANDBY) is not None
            action = Action(system)
            action.arm()
            assert recv(obs, "HEARTBEAT", 10, lambda m: m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED) is not None
            action.disarm()
            obs.close()
        finally:
            sdk.destroy()
    finally:
        code = rig.stop()
    assert code == 0
