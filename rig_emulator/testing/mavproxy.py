"""MAVProxy (PyPI) as a test client of a rig: started on the rig's TCP port, driven through its
stdin and judged by its output (its exit status is not meaningful, its printed lines are).

``scripts/test.sh`` installs MAVProxy (``pip install --no-deps MAVProxy`` plus pyserial) next to
the interpreter running the tests; :data:`MAVPROXY` is where it is expected.

    with MAVProxySession(rig.tcp_url, tmp_path) as mp:
        mp.wait_for(r"Received \\d+ parameters")
        mp.do("param show SMC_K_PHI", r"SMC_K_PHI\\s+1\\.47")
    assert "Traceback" not in mp.before_exit
"""

from __future__ import annotations

import queue
import re
import subprocess
import sys
import threading
from pathlib import Path

MAVPROXY = Path(sys.executable).parent / "mavproxy.py"


class MAVProxySession:
    """One ``mavproxy.py --master=tcp:127.0.0.1:PORT`` process with its state under ``state_dir``
    (also its working directory). ``all`` holds every line printed so far; ``before_exit`` the
    transcript up to the moment :meth:`close` asked MAVProxy to exit (what a test should judge:
    MAVProxy's own shutdown is outside the rig's control)."""

    def __init__(self, tcp_url: str, state_dir, args=()):
        port = tcp_url.rsplit(":", 1)[1]
        self.proc = subprocess.Popen(
            # -u: MAVProxy writes some output (e.g. `status`) to a block-buffered pipe without a flush
            [sys.executable, "-u", str(MAVPROXY), f"--master=tcp:127.0.0.1:{port}", f"--state-basedir={state_dir}",
             *args],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=state_dir)
        self.all: list[str] = []
        self.before_exit = ""
        self._q: queue.Queue = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        for line in self.proc.stdout:
            self.all.append(line)
            self._q.put(line)
        self._q.put(None)

    def transcript(self, last: int | None = None) -> str:
        return "".join(self.all if last is None else self.all[-last:])

    def send(self, line: str) -> None:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def wait_for(self, pattern: str, timeout: float = 60.0):
        """The match of the next line (not yet waited on) matching ``pattern``; None on timeout or exit."""
        while True:
            try:
                line = self._q.get(timeout=timeout)
            except queue.Empty:
                return None
            if line is None:
                return None
            m = re.search(pattern, line)
            if m:
                return m

    def seen_or_wait(self, pattern: str, mark: int, timeout: float = 3.0):
        """A line matching ``pattern`` printed since line ``mark`` (already read or still to come)."""
        for line in self.all[mark:]:
            m = re.search(pattern, line)
            if m:
                return m
        return self.wait_for(pattern, timeout)

    def do(self, line: str, pattern: str | None, timeout: float = 60.0):
        """Send ``line``; with a ``pattern``, the match of the line it brings (AssertionError if none)."""
        self.send(line)
        if pattern is None:
            return None
        got = self.wait_for(pattern, timeout)
        assert got is not None, f"{line!r}: no {pattern!r} in\n" + self.transcript()
        return got

    def close(self) -> None:
        """Ask MAVProxy to exit (``before_exit`` keeps what it printed until then); kill it if it hangs."""
        if self.proc.poll() is None and not self.proc.stdin.closed:
            self.before_exit = self.transcript()
            try:
                self.send("exit")
                self.proc.stdin.close()
                self.proc.wait(30)
            except (OSError, subprocess.TimeoutExpired):
                pass
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()

    def __enter__(self) -> "MAVProxySession":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
