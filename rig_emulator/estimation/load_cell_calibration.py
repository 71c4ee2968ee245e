"""Load-cell calibration, the paper's procedure (Sec. 4-1, Fig. 9, Fig. 10).

``F[grF] = C (S - b)``: first the bias ``b`` is the mean unloaded reading (motors off);
then the 370 g and 685 g reference masses load each arm in turn and ``C`` is the least
squares slope through the origin over every loaded reading of both masses:
``C = sum F_i (S_i - b) / sum (S_i - b)^2``.
Reading: the masses load the cell in the thrust sense (Fig. 10 shows the reading rise)
and the motors are off (rotor speed 0: only the electrical noise floor).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.sensors.load_cell import GRF_N, LoadCellTruth, sample_load_cells


@dataclass
class LoadCellCalibration:
    """Per-cell ``b`` (counts) and ``C`` (grF per count) of ``F = C (S - b)``."""

    zero_counts: np.ndarray
    c_grf_per_count: np.ndarray
    procedure: dict = field(default_factory=dict)


@jit
def _record(thrust_N, n_samples, k, rng, out):
    """``n_samples`` readings of every cell under constant ``thrust_N`` with motors off."""
    n = k.n_cells
    speed = np.zeros(n)
    mode = np.zeros(n, dtype=np.int64)
    magnitude = np.zeros(n)
    raw = np.zeros(n)
    for j in range(n_samples):
        sample_load_cells(thrust_N, speed, k, mode, magnitude, rng, raw)
        for i in range(n):
            out[j, i] = raw[i]


def calibrate_load_cells(params: dict, truth: LoadCellTruth, rng: np.random.Generator) -> LoadCellCalibration:
    """Simulate the procedure on the drawn cells ``truth`` and return ``b`` and ``C``.

    ``params``: the estimation config; its ``load_cell_calibration`` table gives the
    reference masses (grams) and the number of readings per load case.
    """
    proc = params["load_cell_calibration"]
    k = truth.kernel
    n = k.n_cells
    ns = proc["n_samples"]
    unloaded = np.zeros((ns, n))
    _record(np.zeros(n), ns, k, rng, unloaded)
    b = unloaded.mean(axis=0)
    num = np.zeros(n)
    den = np.zeros(n)
    loaded = np.zeros((ns, n))
    for mass_g in proc["masses_g"]:
        _record(np.full(n, mass_g * GRF_N), ns, k, rng, loaded)
        d = loaded - b
        num += mass_g * d.sum(axis=0)
        den += (d * d).sum(axis=0)
    return LoadCellCalibration(b, num / den, {"masses_g": list(proc["masses_g"]), "n_samples": ns})
