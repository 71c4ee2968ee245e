"""Sensor fault modes, switchable at run time (issue 9 builds scenarios on them).

The sampling functions read a per-unit ``mode`` (int64) and ``magnitude`` (float64)
array that the caller may change between steps:

=========  ======  ===================================================================
mode       value   effect on the unit's raw counts
=========  ======  ===================================================================
none       0       healthy
stuck      1       the last raw sample is held (the unit stops updating)
dead       2       all channels read 0 counts
bias       3       ``magnitude`` counts are added to every channel (before clipping)
noise      4       extra white noise of ``magnitude`` x the channel's nominal sigma
spike      5       load cells only: with probability ``spike_probability`` per sample
                   a spike of +-``magnitude`` counts is added
=========  ======  ===================================================================

Reading: the paper reports no fault experiments; these are the usual sensor failure
modes of fault-injection test benches.
"""

from __future__ import annotations

import numpy as np

FAULT_NONE = 0
FAULT_STUCK = 1
FAULT_DEAD = 2
FAULT_BIAS = 3
FAULT_NOISE = 4
FAULT_SPIKE = 5

FAULT_MODES = {"none": FAULT_NONE, "stuck": FAULT_STUCK, "dead": FAULT_DEAD,
               "bias": FAULT_BIAS, "noise": FAULT_NOISE, "spike": FAULT_SPIKE}
IMU_FAULT_MODES = ("none", "stuck", "dead", "bias", "noise")


def set_fault(mode_array: np.ndarray, magnitude_array: np.ndarray, unit: int, mode: str,
              magnitude: float = 0.0, *, imu: bool) -> None:
    """Switch one unit (IMU module or load cell) to a fault mode, validating the names."""
    allowed = IMU_FAULT_MODES if imu else tuple(FAULT_MODES)
    if mode not in allowed:
        raise ValueError(f"fault mode {mode!r}: must be one of {', '.join(allowed)}")
    if not 0 <= unit < mode_array.shape[0]:
        raise ValueError(f"fault unit = {unit}: must be in [0, {mode_array.shape[0] - 1}]")
    if not np.isfinite(magnitude):
        raise ValueError(f"fault magnitude = {magnitude!r}: must be finite")
    mode_array[unit] = FAULT_MODES[mode]
    magnitude_array[unit] = float(magnitude)
