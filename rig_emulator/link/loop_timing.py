"""Wall-clock record of the serve loop's physics chunks (``rig-emulator serve --timing-log FILE``).

The served rig advances its physics in chunks (5 ms of simulated time at speed-up 1) paced
against ``time.monotonic()``: the chunk covering simulated time ``[T, T + chunk]`` is due
once the wall clock reaches the instant that corresponds to ``T + chunk`` (the pacing never
runs ahead of real time). Inside a chunk the control law runs at its fixed simulated rate;
on the wall clock, the chunk is when the controller's outputs come into being. For every
chunk the loop records, in a fixed-size ring buffer (a few array stores, about a
microsecond):

* ``due``: the wall time the pacing scheduled the chunk for (``start`` when unpaced);
* ``start``: the wall time just before the physics step (after the link was serviced);
* ``end``: the wall time after the chunk's telemetry was built and handed to the sockets
  (when the loop runs several chunks in one tick, each builds its own telemetry and they
  share the ``end`` of the last one: the tick's frames go to the sockets together);
* ``sim``: the simulated time at the chunk's start;
* ``sent``: the link's count of messages handed to the sockets so far (after the chunk).

From these, :func:`summarize` derives the figures the jitter benchmark reports: the period
error (spacing of consecutive starts against the nominal chunk period), the lateness
(``start - due``) and the busy time per chunk (``end - start``). All times are
``time.monotonic()`` seconds, which on Linux is one system-wide clock, so another process
(a ground station) can cut the record to the window it was attached.

The record is written once, at exit, as a ``.npz`` (atomically, via
:mod:`protocol.atomic_file`).
"""

from __future__ import annotations

import math
import time

import numpy as np

from protocol.atomic_file import atomic_path

DEFAULT_CAPACITY = 1 << 17  # 131,072 chunks: 11 min at speed-up 1 with 5 ms chunks (5 MiB)
FIELDS = ("due", "start", "end", "sim", "sent")


class LoopTiming:
    """A ring buffer of the last ``capacity`` chunks' ``due``/``start``/``end``/``sim``/``sent``."""

    def __init__(self, chunk_s: float, speedup: float, capacity: int = DEFAULT_CAPACITY):
        if capacity < 2:
            raise ValueError(f"capacity {capacity}: must be >= 2")
        self.chunk_s = float(chunk_s)
        self.speedup = float(speedup)
        self.capacity = int(capacity)
        self._buf = np.full((len(FIELDS), self.capacity), np.nan)
        self.count = 0  # chunks recorded in all (the buffer keeps the last `capacity`)
        self._open = 0  # count of the first chunk begun but not finished
        self.reanchors = 0  # times the pacing gave up catching up (the server's overruns)

    @property
    def period_s(self) -> float:
        """Nominal wall-clock period of a chunk (0 when unpaced)."""
        return self.chunk_s / self.speedup if self.speedup > 0.0 else 0.0

    def begin(self, wall0: float, sim0: float, sim: float) -> None:
        """A chunk starts now at simulated time ``sim``; the pacing maps ``sim0`` to ``wall0``."""
        start = time.monotonic()
        due = wall0 + (sim + self.chunk_s - sim0) / self.speedup if self.speedup > 0.0 else start
        i = self.count % self.capacity
        b = self._buf
        b[0, i] = due
        b[1, i] = start
        b[3, i] = sim
        self.count += 1

    def finish(self, end: float, sent: int) -> None:
        """The chunks begun since the last call are done (their telemetry sent) at ``end``."""
        for k in range(max(self._open, self.count - self.capacity), self.count):
            i = k % self.capacity
            self._buf[2, i] = end
            self._buf[4, i] = sent
        self._open = self.count

    def record(self, due: float, start: float, end: float, sim: float, sent: int = 0) -> None:
        """One whole chunk at once (for loops that compute ``due`` themselves)."""
        i = self.count % self.capacity
        b = self._buf
        b[0, i] = due
        b[1, i] = start
        b[2, i] = end
        b[3, i] = sim
        b[4, i] = sent
        self.count += 1
        self._open = self.count

    def arrays(self) -> dict[str, np.ndarray]:
        """The recorded chunks, oldest first, by field name."""
        n = min(self.count, self.capacity)
        if self.count <= self.capacity:
            data = self._buf[:, :n]
        else:
            i = self.count % self.capacity
            data = np.concatenate([self._buf[:, i:], self._buf[:, :i]], axis=1)
        return {name: data[k].copy() for k, name in enumerate(FIELDS)}

    def write(self, path) -> None:
        """Write the record as ``.npz`` (the arrays plus ``chunk_s``, ``speedup``, ``count``, ``reanchors``)."""
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, chunk_s=self.chunk_s, speedup=self.speedup, count=self.count,
                         reanchors=self.reanchors, **self.arrays())


def load(path) -> dict:
    """A timing log written by :meth:`LoopTiming.write`, as a dict of arrays and scalars."""
    with np.load(path) as z:
        out = {k: z[k] for k in z.files}
    for k in ("chunk_s", "speedup"):
        out[k] = float(out[k])
    for k in ("count", "reanchors"):
        out[k] = int(out[k])
    return out


def _pcts(x: np.ndarray, prefix: str) -> dict[str, float]:
    if x.size == 0:
        return {f"{prefix}_p50_ms": math.nan, f"{prefix}_p99_ms": math.nan, f"{prefix}_max_ms": math.nan}
    p50, p99 = np.percentile(x, [50.0, 99.0])
    return {f"{prefix}_p50_ms": float(p50) * 1e3, f"{prefix}_p99_ms": float(p99) * 1e3,
            f"{prefix}_max_ms": float(np.max(x)) * 1e3}


def summarize(log: dict, t_from: float = -math.inf, t_to: float = math.inf) -> dict[str, float]:
    """Jitter figures of the chunks that started within ``[t_from, t_to]`` (monotonic seconds).

    * ``period_err``: ``|start[k] - start[k-1] - period|`` over consecutive recorded chunks;
    * ``lateness``: ``start - due`` (how long after its scheduled instant a chunk was computed);
    * ``busy``: ``end - start`` (step, telemetry, socket writes);
    * ``sim_per_wall``: simulated seconds per wall second over the window (1.0 = the control
      rate held at speed-up 1), from the first to the last chunk start;
    * ``sent_per_wall``: messages the link handed to its sockets per wall second meanwhile.

    Each as p50 / p99 / max in milliseconds, plus the chunk count.
    """
    start, due, end, sim, sent = (np.asarray(log[k], dtype=float) for k in ("start", "due", "end", "sim", "sent"))
    keep = (start >= t_from) & (start <= t_to)
    start, due, end, sim, sent = start[keep], due[keep], end[keep], sim[keep], sent[keep]
    period = float(log["chunk_s"]) / float(log["speedup"]) if float(log["speedup"]) > 0 else math.nan
    out: dict[str, float] = {"chunks": int(start.size), "nominal_period_ms": period * 1e3}
    spacing = np.diff(start)
    out.update(_pcts(np.abs(spacing - period), "period_err"))
    out.update(_pcts(start - due, "lateness"))
    out.update(_pcts(end - start, "busy"))
    if start.size >= 2 and start[-1] > start[0]:
        out["sim_per_wall"] = float((sim[-1] - sim[0]) / (start[-1] - start[0]))
        out["sent_per_wall"] = float((sent[-1] - sent[0]) / (start[-1] - start[0]))
        out["window_s"] = float(start[-1] - start[0])
    else:
        out["sim_per_wall"] = out["sent_per_wall"] = math.nan
        out["window_s"] = 0.0
    out["late_over_1ms_fraction"] = float(np.mean(start - due > 1e-3)) if start.size else math.nan
    return out
