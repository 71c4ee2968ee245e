"""Load-cell thrust chain: calibration, the paper's guards, then a smoothing filter.

Per load-cell sample (period ``dt_s``) and cell:

1. ``F = C (S - b)`` (Sec. 4-1), in newtons (1 grF = 9.80665e-3 N).
2. Guards (Sec. 3-2): a reading above ``max_thrust_grf`` (850 grF, the propeller's
   ceiling) is discarded, and a reading that jumps from the previous accepted one by more
   than ``jump_threshold_grf`` is replaced by the previous accepted value. Reading: the
   paper never re-accepts; here after ``reaccept_after`` consecutive rejections a reading
   within the bounds is accepted again, so a genuine fast thrust change cannot lock the
   guard forever (``reaccept_after = 0`` is the paper-faithful "never"). Reading (
   the paper's "reasonable bound for every variable"): a reading below ``min_thrust_grf``
   is discarded like one above the ceiling - a cell under a motor cannot be pulled up by
   hundreds of gram-force, but a dead cell (0 counts) reads about ``-C b`` = -850 grF, which
   the jump guard alone would re-accept. The first reading is accepted if within the
   bounds (else 0).
3. Filter (``mode``): ``"none"``; ``"iir"``, the paper's first-order IIR low-pass
   ``y += alpha (x - y)`` with ``alpha = 1 - exp(-2 pi f_c dt)``; or ``"kalman"``, a
   steady-state Kalman filter of the 2-state model thrust + thrust rate driven by white
   thrust acceleration (spectral density ``kalman_accel_noise_grf_per_s2_rthz^2``) and
   measured with noise ``kalman_measurement_sigma_grf``. Its gain is designed offline from
   the discrete algebraic Riccati equation (scipy) and applied in compiled code
   (PERFORMANCE-NOTES: filterpy's per-update cost is too high for the 1 kHz loop).
   Reading: the model needs no knowledge of the commanded thrust; for a ramp its
   steady-state lag is zero where the IIR lags by its time constant.

Both filters run on every sample and ``mode`` selects the output, so the mode can be
switched at run time without a transient. Outputs thrust per cell in newtons. Filter state ``(n_cells, 6)``: accepted reading,
IIR output, Kalman thrust, Kalman thrust rate, consecutive rejections, initialised.
"""

from __future__ import annotations

import functools
import math
from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.sensors.load_cell import GRF_N

FILTER_NONE = 0
FILTER_IIR = 1
FILTER_KALMAN = 2
FILTER_MODES = {"none": FILTER_NONE, "iir": FILTER_IIR, "kalman": FILTER_KALMAN}

LcFilterParams = namedtuple(
    "LcFilterParams",
    ["mode", "zero_counts", "newton_per_count", "jump_threshold_N", "max_thrust_N", "min_thrust_N",
     "reaccept_after", "iir_alpha", "kalman_gain", "dt_s"],
)


def thrust_kalman_model(dt_s: float, sigma_meas_N: float, accel_noise_N_per_s2_rthz: float):
    """(F, H, Q, R) of the discrete constant-rate thrust model (white-acceleration)."""
    q = accel_noise_N_per_s2_rthz ** 2
    F = np.array([[1.0, dt_s], [0.0, 1.0]])
    H = np.array([[1.0, 0.0]])
    Q = q * np.array([[dt_s ** 3 / 3.0, dt_s ** 2 / 2.0], [dt_s ** 2 / 2.0, dt_s]])
    R = np.array([[sigma_meas_N ** 2]])
    return F, H, Q, R


def design_thrust_kalman_gain(dt_s: float, sigma_meas_N: float, accel_noise_N_per_s2_rthz: float) -> np.ndarray:
    """Steady-state Kalman gain (2,) of :func:`thrust_kalman_model` from the DARE.

    Designed once per parameter set and process (a fresh copy each call): every rig that
    is built needs it, and scipy's DARE wakes OpenBLAS's worker threads, which then
    busy-wait for tens of milliseconds; on a loaded 2-core machine they take CPU from the
    step loop that starts right after.
    """
    return _design_thrust_kalman_gain(float(dt_s), float(sigma_meas_N), float(accel_noise_N_per_s2_rthz)).copy()


@functools.lru_cache(maxsize=32)
def _design_thrust_kalman_gain(dt_s: float, sigma_meas_N: float, accel_noise_N_per_s2_rthz: float) -> np.ndarray:
    F, H, Q, R = thrust_kalman_model(dt_s, sigma_meas_N, accel_noise_N_per_s2_rthz)
    from scipy.linalg import solve_discrete_are  # imported when first needed (start-up time)

    P = solve_discrete_are(F.T, H.T, Q, R)  # prior covariance
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    return np.ascontiguousarray(K[:, 0])


def load_cell_filter_params(est_cfg: dict, calibration, dt_s: float) -> LcFilterParams:
    """Compiled-side parameters from the ``load_cell_filter`` table, a LoadCellCalibration
    and the load-cell sample period ``dt_s`` (decimation x physics step)."""
    c = est_cfg["load_cell_filter"]
    return LcFilterParams(
        mode=FILTER_MODES[c["mode"]],
        zero_counts=np.ascontiguousarray(calibration.zero_counts, dtype=np.float64),
        newton_per_count=np.ascontiguousarray(calibration.c_grf_per_count * GRF_N, dtype=np.float64),
        jump_threshold_N=c["jump_threshold_grf"] * GRF_N,
        max_thrust_N=c["max_thrust_grf"] * GRF_N,
        min_thrust_N=c["min_thrust_grf"] * GRF_N,
        reaccept_after=c["reaccept_after"],
        iir_alpha=1.0 - math.exp(-2.0 * math.pi * c["iir_cutoff_hz"] * dt_s),
        kalman_gain=design_thrust_kalman_gain(dt_s, c["kalman_measurement_sigma_grf"] * GRF_N,
                                              c["kalman_accel_noise_grf_per_s2_rthz"] * GRF_N),
        dt_s=float(dt_s),
    )


def load_cell_filter_state(n_cells: int) -> np.ndarray:
    return np.zeros((n_cells, 6))


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def load_cell_filter_step(raw_counts, p, state, out_N):
    """One load-cell sample: guards + filter; writes thrust [N] per cell into ``out_N``.

    Returns the bit mask of cells whose reading was rejected by a guard this sample.
    """
    rejected = 0
    k0 = p.kalman_gain[0]
    k1 = p.kalman_gain[1]
    for i in range(raw_counts.shape[0]):
        f = p.newton_per_count[i] * (raw_counts[i] - p.zero_counts[i])
        if state[i, 5] == 0.0:
            x = f if f >= p.min_thrust_N and f <= p.max_thrust_N else 0.0
            state[i, 0] = x
            state[i, 1] = x
            state[i, 2] = x
            state[i, 3] = 0.0
            state[i, 4] = 0.0
            state[i, 5] = 1.0
        else:
            prev = state[i, 0]
            in_bounds = f >= p.min_thrust_N and f <= p.max_thrust_N
            if not in_bounds or abs(f - prev) > p.jump_threshold_N:
                rejected |= 1 << i
                state[i, 4] += 1.0
                if p.reaccept_after > 0 and state[i, 4] >= p.reaccept_after and in_bounds:
                    state[i, 0] = f
                    state[i, 4] = 0.0
            else:
                state[i, 0] = f
                state[i, 4] = 0.0
            x = state[i, 0]
            state[i, 1] += p.iir_alpha * (x - state[i, 1])
            fp = state[i, 2] + p.dt_s * state[i, 3]
            innov = x - fp
            state[i, 2] = fp + k0 * innov
            state[i, 3] += k1 * innov
        if p.mode == FILTER_IIR:
            out_N[i] = state[i, 1]
        elif p.mode == FILTER_KALMAN:
            out_N[i] = state[i, 2]
        else:
            out_N[i] = state[i, 0]
    return rejected
