"""MAVProxy (PyPI) against the running rig: connects, fetches every parameter, shows attitude.

MAVProxy is driven through its stdin; its exit status is not meaningful, its output is.
``scripts/test.sh`` installs it (``pip install --no-deps MAVProxy`` plus pyserial); the test fails
without it rather than passing silently.
"""

import queue
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.rig import RigProcess

MAVPROXY = Path(sys.executable).parent / "mavproxy.py"
pytestmark = [pytest.mark.slow]


def test_mavproxy_is_installed():
    assert MAVPROXY.exists(), "MAVProxy is a test requirement: run scripts/test.sh or pip install --no-deps MAVProxy"


class _Lines:
    def __init__(self, proc):
        self.q, self.all = queue.Queue(), []
        threading.Thread(target=self._pump, args=(proc,), daemon=True).start()

    def _pump(self, proc):
        for line in proc.stdout:
            self.all.append(line)
            self.q.put(line)
        self.q.put(None)

    def wait_for(self, pattern: str, timeout: float = 60.0):
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


def test_mavproxy_fetches_params_and_shows_attitude(tmp_path):
    with RigProcess(speedup=1.0) as rig:
        port = rig.tcp_url.rsplit(":", 1)[1]
        proc = subprocess.Popen(
            [sys.executable, str(MAVPROXY), f"--master=tcp:127.0.0.1:{port}", f"--state-basedir={tmp_path}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
        out = _Lines(proc)
        try:
            got = out.wait_for(r"Received (\d+) parameters")
            assert got is not None, "".join(out.all)
            assert int(got.group(1)) == len(ParamTable())
            proc.stdin.write("param show SMC_K_PHI\n")
            proc.stdin.flush()
            assert out.wait_for(r"SMC_K_PHI\s+1\.47") is not None, "".join(out.all)
            proc.stdin.write("status ATTITUDE\n")
            proc.stdin.flush()
            att = out.wait_for(r"ATTITUDE \{time_boot_ms : \d+, roll : (\S+),")
            assert att is not None, "".join(out.all)
            before_exit = "".join(out.all)
            proc.stdin.write("exit\n")
            proc.stdin.close()
            proc.wait(30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        # judged while connected: MAVProxy's own shutdown is outside the rig's control
        assert "Traceback" not in before_exit and "Exception" not in before_exit, before_exit
        assert rig.stop() == 0
