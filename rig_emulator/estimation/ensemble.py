"""Ensemble of the calibrated IMU modules (paper Sec. 4-1).

The paper averages the five calibrated modules "to lower the adverse effects of
high-frequency noises" (``mode = "mean"``). A plain average follows any failed module, so
two robust options are offered (Reading: not in the paper):

* ``"median"``: the per-axis median of the modules;
* ``"robust_mean"``: the mean of the modules whose vector lies within
  ``reject_threshold`` (Euclidean) of the per-axis median; the others are rejected.
  If every module is rejected the median is used.

Each call returns a bit mask of the modules rejected (bit m = module m) for health
reporting (MAVLink SYS_STATUS later); ``mean`` and ``median`` never reject.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.sensors.sensor_step import SAMPLED_INERTIAL, SAMPLED_MAG

ENSEMBLE_MEAN = 0
ENSEMBLE_MEDIAN = 1
ENSEMBLE_ROBUST_MEAN = 2
ENSEMBLE_MODES = {"mean": ENSEMBLE_MEAN, "median": ENSEMBLE_MEDIAN, "robust_mean": ENSEMBLE_ROBUST_MEAN}

EnsembleParams = namedtuple("EnsembleParams", ["mode", "reject_threshold"])  # int, (3,) SI per sensor
EnsembleState = namedtuple("EnsembleState", ["scratch", "rejected"])  # (n,) float, (3,) int64 per sensor


def ensemble_params(est_cfg: dict) -> EnsembleParams:
    """Compiled-side parameters from the estimation config's ``ensemble`` table."""
    e = est_cfg["ensemble"]
    thr = np.array([math.radians(e["gyro_reject_dps"]), e["accel_reject_m_s2"], e["mag_reject_uT"] * 1e-6])
    return EnsembleParams(ENSEMBLE_MODES[e["mode"]], thr)


def ensemble_state(n_modules: int) -> EnsembleState:
    return EnsembleState(np.zeros(n_modules), np.zeros(3, dtype=np.int64))


@jit(inline="always")
def _median5(p0, p1, p2, p3, p4):
    """Median of five numbers by the seven compare-exchanges of Devillard's opt_med5 (no scratch)."""
    if p0 > p1:
        p0, p1 = p1, p0
    if p3 > p4:
        p3, p4 = p4, p3
    if p0 > p3:
        p0, p3 = p3, p0
    if p1 > p4:
        p1, p4 = p4, p1
    if p1 > p2:
        p1, p2 = p2, p1
    if p2 > p3:
        p2, p3 = p3, p2
    if p1 > p2:
        p1, p2 = p2, p1
    return p2


@jit(inline="always")
def _median_axis(values, s, axis, scratch):
    n = values.shape[0]
    if n == 5:
        return _median5(values[0, s, axis], values[1, s, axis], values[2, s, axis],
                        values[3, s, axis], values[4, s, axis])
    for m in range(n):  # insertion sort into scratch
        v = values[m, s, axis]
        j = m
        while j > 0 and scratch[j - 1] > v:
            scratch[j] = scratch[j - 1]
            j -= 1
        scratch[j] = v
    h = n // 2
    if n % 2 == 1:
        return scratch[h]
    return 0.5 * (scratch[h - 1] + scratch[h])


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def ensemble_vectors(values, s, mode, threshold, scratch, out):
    """Combine sensor ``s`` of every module ``values[m, s, :]`` into ``out`` (3,).

    Returns the bit mask of rejected modules.
    """
    n = values.shape[0]
    if mode == ENSEMBLE_MEAN:
        for i in range(3):
            acc = 0.0
            for m in range(n):
                acc += values[m, s, i]
            out[i] = acc / n
        return 0
    med0 = _median_axis(values, s, 0, scratch)
    med1 = _median_axis(values, s, 1, scratch)
    med2 = _median_axis(values, s, 2, scratch)
    if mode == ENSEMBLE_MEDIAN:
        out[0] = med0
        out[1] = med1
        out[2] = med2
        return 0
    thr2 = threshold * threshold
    rejected = 0
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    kept = 0
    for m in range(n):
        d0 = values[m, s, 0] - med0
        d1 = values[m, s, 1] - med1
        d2 = values[m, s, 2] - med2
        if d0 * d0 + d1 * d1 + d2 * d2 > thr2:
            rejected |= 1 << m
        else:
            a0 += values[m, s, 0]
            a1 += values[m, s, 1]
            a2 += values[m, s, 2]
            kept += 1
    if kept == 0:
        out[0] = med0
        out[1] = med1
        out[2] = med2
    else:
        out[0] = a0 / kept
        out[1] = a1 / kept
        out[2] = a2 / kept
    return rejected


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def ensemble_step(values, sampled_mask, p, state, out):
    """Ensemble of gyro and accel (if ``SAMPLED_INERTIAL``) and mag (if ``SAMPLED_MAG``).

    ``values`` (n, 3, 3) calibrated SI ``[module, sensor, axis]``; ``out`` (3, 3)
    ``[sensor, axis]`` (rows not due keep their previous values). Returns the health mask:
    the OR over sensors of the modules rejected at their latest sample.
    """
    thr = p.reject_threshold
    # np.int64(): a literal constant argument would compile one specialisation per value
    if sampled_mask & SAMPLED_INERTIAL:
        state.rejected[0] = ensemble_vectors(values, np.int64(0), p.mode, thr[0], state.scratch, out[0])
        state.rejected[1] = ensemble_vectors(values, np.int64(1), p.mode, thr[1], state.scratch, out[1])
    if sampled_mask & SAMPLED_MAG:
        state.rejected[2] = ensemble_vectors(values, np.int64(2), p.mode, thr[2], state.scratch, out[2])
    return state.rejected[0] | state.rejected[1] | state.rejected[2]
