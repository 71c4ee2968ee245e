"""A thread that runs the served rig's compiled step loop while the serve loop builds telemetry.

At ``--speedup max`` the serve loop is CPU-bound on one core (issue 14, benchmarks/README.md
"served-max"): per chunk of 20 ms of simulated time it runs the compiled step loop, then
builds, encodes and queues the chunk's telemetry in Python. The step loop is compiled with
``nogil=True`` (:func:`rig_emulator.simulation.loop.run_steps`): while it runs, another
thread can hold the GIL. :class:`StepWorker` runs one call at a time on its own thread:
the server hands it chunk k + 1 (:meth:`LiveRig.step_start <rig_emulator.simulation.live.LiveRig.step_start>`)
after chunk k's snapshot was taken and its commands applied, sends chunk k's telemetry
meanwhile, then waits for the result (:meth:`LiveRig.step_finish`).

numba's entry point needs the GIL to unbox the arguments before the loop and to box its
result after; a thread waiting for the GIL gets it only when the holder drops it, by default
after CPython's 5 ms switch interval. :func:`short_switch_interval` shortens that while the
worker is in use, so that the hand-offs cost microseconds.
"""

from __future__ import annotations

import contextlib
import sys
import threading

SWITCH_INTERVAL_S = 2e-5  # CPython's GIL switch interval while the worker runs (default 5e-3)


class StepWorker:
    """One call at a time on a daemon thread: :meth:`submit`, then the getter it returns."""

    def __init__(self, name: str = "rig-step"):
        self._go = threading.Lock()
        self._go.acquire()
        self._done = threading.Lock()
        self._done.acquire()
        self._job = None
        self._result = None
        self._exc = None
        self._busy = False
        self._closed = False
        self._thread = threading.Thread(target=self._main, name=name, daemon=True)
        self._thread.start()

    def _main(self) -> None:
        go, done = self._go, self._done
        while True:
            go.acquire()
            job = self._job
            if job is None:
                done.release()
                return
            fn, args = job
            try:
                self._result = fn(*args)
            except BaseException as exc:  # noqa: BLE001 - handed to the caller, raised by result()
                self._exc = exc
            self._job = None
            done.release()

    def submit(self, fn, args: tuple):
        """Start ``fn(*args)`` on the worker; returns :meth:`result` (call it before the next submit)."""
        if self._busy or self._closed:
            raise RuntimeError("StepWorker: a call is running already" if self._busy else "StepWorker: closed")
        self._job = (fn, args)
        self._busy = True
        self._go.release()
        return self.result

    def result(self):
        """Wait for the running call; its return value, or its exception raised here."""
        if not self._busy:
            raise RuntimeError("StepWorker: no call is running")
        self._done.acquire()
        self._busy = False
        exc, self._exc = self._exc, None
        result, self._result = self._result, None
        if exc is not None:
            raise exc
        return result

    @property
    def busy(self) -> bool:
        return self._busy

    def close(self) -> None:
        """Wait for a running call (its outcome dropped) and end the thread."""
        if self._closed:
            return
        if self._busy:
            with contextlib.suppress(BaseException):
                self.result()
        self._closed = True
        self._job = None
        self._go.release()
        self._thread.join()


@contextlib.contextmanager
def short_switch_interval(seconds: float = SWITCH_INTERVAL_S):
    """CPython's GIL switch interval set to ``seconds`` inside the block (restored after)."""
    previous = sys.getswitchinterval()
    sys.setswitchinterval(seconds)
    try:
        yield
    finally:
        sys.setswitchinterval(previous)
