"""What the flight-stack studies share: starting and stopping the rig and the flight stack as
processes, and the figures they take from a flight (:mod:`.px4_reposition`, :mod:`.ardupilot_move`)."""

from __future__ import annotations

import math
import os
import signal
import socket
import subprocess
import sys
import threading


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


def span(values: list[float], digits: int) -> str:
    """``lo-hi`` of ``values`` at ``digits`` decimals (one number where both round alike; ``lo to hi``
    where ``lo`` is negative, which a hyphen would hide)."""
    lo, hi = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    if lo == hi:
        return lo
    return f"{lo} to {hi}" if lo.startswith("-") else f"{lo}-{hi}"
