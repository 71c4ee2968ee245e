"""A headless run of any length in bounded memory, stoppable between chunks.

:meth:`Simulation.run <rig_emulator.simulation.run.Simulation.run>` keeps the whole series in
memory (what the Python API returns). ``rig-emulator simulate`` instead runs the compiled
loop in chunks of :data:`CHUNK_ROWS` log rows into one reused log buffer and hands each
chunk to the sinks that want it (a series file being written, the mean-error accumulator):
its memory does not grow with the duration. Running in chunks changes nothing in the
simulation (the loop takes its start step and log row as arguments; the fault schedule
already splits calls), so the rows are bit for bit those of a single call.

A stop request (:meth:`StreamedRun.request_stop`, e.g. from a SIGINT handler) ends the run
after the chunk being simulated; what was simulated so far stays valid.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from protocol.mean_error import MeanErrorAccumulator
from rig_emulator.config.loader import RigConfig
from rig_emulator.simulation import log_layout as L
from rig_emulator.simulation.run import Simulation

CHUNK_ROWS = 8192  # log rows per compiled call: 82 s of simulated time at the default 100 Hz log, 4 MB


@dataclass
class StreamedResult:
    """What a streamed run leaves: its figures, not its series (those went to the sinks)."""

    config: RigConfig
    steps: int
    rows: int
    sim_time_s: float
    wall_time_s: float
    mean_errors: dict
    reached_t: np.ndarray
    failsafe: tuple | None  # (t_s, cause code) of the first row with the failsafe latched
    interrupted: bool = False
    extra: dict = field(default_factory=dict)

    @property
    def real_time_factor(self) -> float:
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else math.inf


class StreamedRun:
    """Run ``cfg`` for its ``sim.duration`` in chunks; ``sinks`` get every chunk of log rows."""

    def __init__(self, cfg: RigConfig, chunk_rows: int = CHUNK_ROWS):
        self.sim = Simulation(cfg, log_capacity=chunk_rows + 1)
        self.chunk_steps = chunk_rows * self.sim.log_div
        self._stop = False

    def request_stop(self) -> None:
        """End the run after the chunk being simulated (safe from a signal handler)."""
        self._stop = True

    def warm_up(self) -> float:
        return self.sim.warm_up()

    def run(self, sinks=()) -> StreamedResult:
        sim = self.sim
        n_steps = int(round(sim.cfg["sim.duration"] / sim.dt))
        errors = MeanErrorAccumulator()
        failsafe = None
        rows = 0
        wall = 0.0
        done = 0
        while done < n_steps and not self._stop:
            n = min(self.chunk_steps, n_steps - done)
            sim.log_row = 0
            t0 = time.perf_counter()
            sim.advance(n)
            wall += time.perf_counter() - t0
            if sim.plugin_failure is not None:  # a controller plug-in failed: stop with its message
                raise sim.plugin_failure
            done += n
            chunk = sim.log[: sim.log_row]
            rows += chunk.shape[0]
            errors.add(chunk[:, L.EULER : L.EULER + 3], chunk[:, L.EULER_DES : L.EULER_DES + 3],
                       chunk[:, L.POS : L.POS + 3], chunk[:, L.POS_DES : L.POS_DES + 3])
            if failsafe is None:
                tripped = np.flatnonzero(chunk[:, L.FAILSAFE] > 0)
                if tripped.size:
                    failsafe = (float(chunk[tripped[0], L.T]), int(chunk[tripped[0], L.FAILSAFE]))
            for sink in sinks:
                sink.write(chunk)
        return StreamedResult(config=sim.cfg, steps=done, rows=rows, sim_time_s=done * sim.dt, wall_time_s=wall,
                              mean_errors=errors.result(), reached_t=sim.reached_t.copy(), failsafe=failsafe,
                              interrupted=done < n_steps)
