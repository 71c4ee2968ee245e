"""A served rig (``rig-emulator serve`` in a subprocess) for the link, jitter and memory benchmarks.

:func:`ensure_compiled` first starts and stops a throw-away rig, so that the numba cache of
the run is warm and the measured rig loads it instead of compiling (a compiling process is
busy for a minute and its memory holds LLVM's working set). :class:`ServedRig` then starts
the measured rig with ``--timing-log`` in a temporary directory, exposes its pid (for
``/proc`` figures) and, once stopped, its chunk timing record
(:mod:`rig_emulator.link.loop_timing`).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time

from .harness import BenchmarkUnavailable


def _testing():
    try:
        from rig_emulator.testing import rig as testing
    except ImportError as exc:
        raise BenchmarkUnavailable(f"rig_emulator.testing.rig is not importable: {type(exc).__name__}: {exc}") from None
    return testing


def ensure_compiled() -> float:
    """Start and stop a rig (``--speedup max --duration 0.05``); returns its wall seconds.

    The probes take ``warm_up=False`` to skip this where the cache is known to be warm (tests).
    """
    testing = _testing()
    t0 = time.perf_counter()
    rig = testing.RigProcess(speedup="max", args=["--duration", "0.05"])
    try:
        code = rig.proc.wait(testing.START_TIMEOUT_S)
    finally:
        rig.stop()
    if code != 0:
        raise RuntimeError(f"warm-up rig exited with {code}: {rig.output[-5:]}")
    return time.perf_counter() - t0


class ServedRig:
    """``RigProcess`` at ``speedup`` with a chunk timing log; use as a context manager."""

    def __init__(self, speedup: float | str = 1.0, args=(), timing: bool = True, extra_endpoints=()):
        testing = _testing()
        self._tmp = tempfile.mkdtemp(prefix="hilms-bench-rig-")
        self.timing_path = os.path.join(self._tmp, "timing.npz") if timing else None
        extra = ["--timing-log", self.timing_path] if timing else []
        t0 = time.perf_counter()
        self.rig = testing.RigProcess(speedup=speedup, args=[*extra, *args], extra_endpoints=extra_endpoints)
        self.start_s = time.perf_counter() - t0
        self.exit_code = None

    @property
    def pid(self) -> int:
        return self.rig.proc.pid

    @property
    def tcp_url(self) -> str:
        return self.rig.tcp_url

    @property
    def urls(self) -> list[str]:
        return self.rig.urls

    def stop(self) -> int:
        if self.exit_code is None:
            self.exit_code = self.rig.stop()
        return self.exit_code

    def timing(self) -> dict:
        """The chunk timing record (after :meth:`stop`)."""
        from rig_emulator.link import loop_timing

        if self.timing_path is None:
            raise RuntimeError("this rig was started without a timing log")
        if self.exit_code is None:
            raise RuntimeError("stop the rig before reading its timing log")
        if self.exit_code != 0 or not os.path.exists(self.timing_path):
            raise RuntimeError(f"rig exited with {self.exit_code} and wrote no timing log: {self.rig.output[-5:]}")
        return loop_timing.load(self.timing_path)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        try:
            self.stop()
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)
