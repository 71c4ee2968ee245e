"""What the flight-stack studies share: starting and stopping the rig and the flight stack as
processes, and the figures they take from a flight (:mod:`.px4_reposition`, :mod:`.ardupilot_move`)."""

from __future__ import annotations

import abc
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_rig(args: list[str], ready: str, seconds: float = 300.0) -> subprocess.Popen:
    """``rig-emulator serve ARGS`` as a process of this Python, once it has printed ``ready``
    (the first run may compile the step loop first)."""
    proc = subprocess.Popen([sys.executable, "-m", "rig_emulator", "serve", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=dict(os.environ, PYTHONUNBUFFERED="1"))
    lines: list[str] = []
    seen = threading.Event()

    def read():
        for line in proc.stdout:
            lines.append(line)
            if ready in line:
                seen.set()

    threading.Thread(target=read, daemon=True).start()
    if not seen.wait(seconds):
        stop(proc, signal.SIGINT)
        raise RuntimeError(f"the rig did not print {ready!r} in {seconds:g} s: {''.join(lines[-5:])}")
    proc.lines = lines  # what it printed, for a report
    return proc


def stop(proc: subprocess.Popen | None, sig: int = signal.SIGTERM, seconds: float = 20.0) -> None:
    """Stop ``proc`` with ``sig``, killing it after ``seconds``."""
    if proc is None or proc.poll() is not None:
        return
    proc.send_signal(sig)
    try:
        proc.wait(seconds)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def wrap(a: float) -> float:
    """An angle in [-pi, pi) (rad)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def tilt_deg(roll: float, pitch: float) -> float:
    """The tilt of the vertical axis, ``acos(cos roll cos pitch)`` (rad in, deg out)."""
    return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch)))))


def chosen(text: str, known, option: str, error) -> list[str]:
    """The comma-separated names of ``text``, each one of ``known``; ``error(message)`` (a parser's)
    names ``option`` and the unknown ones otherwise."""
    names = [n.strip() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in known]
    if bad or not names:
        error(f"{option}: {', '.join(bad) or 'none given'}: must be of {', '.join(known)}")
    return names


def git_commit(tree) -> str:
    """The short commit a source tree (a flight stack's) is checked out at, or "unknown"."""
    done = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short=9", "HEAD"], capture_output=True, text=True)
    return done.stdout.strip() or "unknown"


class StackLink(abc.ABC):
    """A flight stack's MAVLink link, timed in the flight stack's own (simulated) clock.

    A subclass sets ``link`` (its pymavlink connection), ``target`` (system, component), keeps ``t``
    (the stack's time, s) and ``acks`` (command -> result) up to date in ``pump(rows)``."""

    ack_wait_s = 1.0  # wall time to wait for each COMMAND_ACK before sending again

    @abc.abstractmethod
    def pump(self, rows: list | None = None):
        """Read what the links have; the stack's samples for a figure go into ``rows`` (if the subclass keeps any)."""

    def wait(self, seconds: float, rows: list | None = None, until=None, wall_limit: float = 900.0) -> bool:
        """Pump for ``seconds`` of the stack's time (or until ``until()``); False on the wall-clock limit."""
        t0, w0 = self.t, time.monotonic()
        while self.t - t0 < seconds:
            self.pump(rows)
            if until is not None and until():
                return True
            if time.monotonic() - w0 > wall_limit:
                return False
        return until is None

    def command(self, command: int, *p: float, tries: int = 10):
        """COMMAND_LONG ``command`` with params ``p``, sent until acknowledged: the result (None: never)."""
        p = list(p) + [0.0] * (7 - len(p))
        return self.acked(command, lambda: self.link.mav.command_long_send(*self.target, command, 0, *p), tries)

    def acked(self, command: int, send, tries: int = 10):
        """Call ``send()`` (a COMMAND_LONG or COMMAND_INT of ``command``) until the stack acknowledges it:
        the result (None: never, after ``tries`` sends)."""
        for _ in range(tries):
            self.acks.pop(command, None)
            send()
            w0 = time.monotonic()
            while time.monotonic() - w0 < self.ack_wait_s:
                self.pump()
                if command in self.acks:
                    return self.acks[command]
        return None
