"""Fault modes of the rig's devices, switchable at run time.

The sensor sampling functions read a per-unit ``mode`` (int64) and ``magnitude`` (float64)
array that the caller may change between steps; a motor fault is a per-motor thrust
efficiency in :class:`~rig_emulator.simulation.params.PhysicsParams` (the physics
multiplies Eq. 40's thrust by it):

===========  ======  =================================================================
mode         value   effect
===========  ======  =================================================================
none         0       healthy (injecting it clears a fault)
stuck        1       sensors: the last raw sample is held (the unit stops updating)
dead         2       sensors: all channels read 0 counts; motor: no thrust at all
bias         3       sensors: ``magnitude`` counts are added to every channel (before clipping)
noise        4       sensors: extra white noise of ``magnitude`` x the channel's nominal sigma
spike        5       load cells only: with probability ``spike_probability`` per sample
                     a spike of +-``magnitude`` counts is added
thrust_loss  6       motors only: the motor produces ``1 - magnitude`` of its thrust
                     (``magnitude`` in [0, 1] is the fraction lost)
===========  ======  =================================================================

The codes are the dialect's ``HILMS_FAULT`` values. Devices are numbered as the rig's
documents number them: IMU modules 0..n-1, load cells and motors 1..4 (the arm number, A6).

Reading: the paper reports no fault experiments; these are the usual failure modes of
fault-injection test benches. A motor fault reduces the motor's whole output (thrust,
rotor speed through F = kF Omega^2 and reaction moment), like a weak motor or driver; the
load cell under that motor measures the thrust the motor really produces.
"""

from __future__ import annotations

import math

import numpy as np

FAULT_NONE = 0
FAULT_STUCK = 1
FAULT_DEAD = 2
FAULT_BIAS = 3
FAULT_NOISE = 4
FAULT_SPIKE = 5
FAULT_THRUST_LOSS = 6

FAULT_MODES = {"none": FAULT_NONE, "stuck": FAULT_STUCK, "dead": FAULT_DEAD, "bias": FAULT_BIAS,
               "noise": FAULT_NOISE, "spike": FAULT_SPIKE, "thrust_loss": FAULT_THRUST_LOSS}
FAULT_NAMES = {code: name for name, code in FAULT_MODES.items()}
IMU_FAULT_MODES = ("none", "stuck", "dead", "bias", "noise")
CELL_FAULT_MODES = ("none", "stuck", "dead", "bias", "noise", "spike")
MOTOR_FAULT_MODES = ("none", "dead", "thrust_loss")

DEVICES = ("imu", "load_cell", "motor")
DEVICE_MODES = {"imu": IMU_FAULT_MODES, "load_cell": CELL_FAULT_MODES, "motor": MOTOR_FAULT_MODES}
FIRST_INDEX = {"imu": 0, "load_cell": 1, "motor": 1}  # IMU modules from 0, arms from 1
_LABELS = {"imu": "IMU module", "load_cell": "load cell", "motor": "motor"}
_WITH_ARTICLE = {"imu": "an IMU module", "load_cell": "a load cell", "motor": "a motor"}
MAX_MAGNITUDE = 1e6


def device_label(device: str, index: int) -> str:
    """'IMU module 2', 'load cell 3', 'motor 1'."""
    return f"{_LABELS[device]} {index}"


def check_fault(device: str, index: int, mode: str, magnitude: float, n_units: int) -> float:
    """Validate one fault for a device with ``n_units`` units; returns the magnitude it uses.

    Raises ``ValueError`` saying what is wrong: an unknown device or mode, a mode the device
    does not have, an index out of range, a magnitude out of its mode's range. Modes without
    a magnitude (none, stuck, dead) return 0.
    """
    if device not in DEVICE_MODES:
        raise ValueError(f"device {device!r}: must be one of {', '.join(DEVICES)}")
    allowed = DEVICE_MODES[device]
    if mode not in allowed:
        raise ValueError(f"fault {mode!r} does not apply to {_WITH_ARTICLE[device]}: use one of {', '.join(allowed)}")
    first = FIRST_INDEX[device]
    last = first + n_units - 1
    if isinstance(index, bool) or int(index) != index or not first <= index <= last:
        raise ValueError(f"{_LABELS[device]} {index}: must be {first}..{last}")
    if mode in ("none", "stuck", "dead"):
        return 0.0
    m = float(magnitude)
    if not math.isfinite(m):
        raise ValueError(f"{mode} magnitude {magnitude!r}: must be finite")
    if mode == "thrust_loss":
        if not 0.0 <= m <= 1.0:
            raise ValueError(f"thrust_loss fraction {m:g}: must be in [0, 1] (the fraction of thrust lost)")
    elif mode == "bias":
        if abs(m) > MAX_MAGNITUDE:
            raise ValueError(f"bias {m:g} counts: must be in [-{MAX_MAGNITUDE:g}, {MAX_MAGNITUDE:g}]")
    elif not 0.0 <= m <= MAX_MAGNITUDE:  # noise (x sigma), spike (counts)
        raise ValueError(f"{mode} magnitude {m:g}: must be in [0, {MAX_MAGNITUDE:g}]")
    return m


def thrust_efficiency(mode: str, magnitude: float) -> float:
    """The share of its thrust a motor in fault ``mode`` still produces."""
    if mode == "dead":
        return 0.0
    if mode == "thrust_loss":
        return 1.0 - magnitude
    return 1.0


def set_fault(mode_array: np.ndarray, magnitude_array: np.ndarray, unit: int, mode: str,
              magnitude: float = 0.0, *, imu: bool) -> None:
    """Switch one sensor unit (array position ``unit``, from 0) to a fault mode, validating the names."""
    allowed = IMU_FAULT_MODES if imu else CELL_FAULT_MODES
    if mode not in allowed:
        raise ValueError(f"fault mode {mode!r}: must be one of {', '.join(allowed)}")
    if not 0 <= unit < mode_array.shape[0]:
        raise ValueError(f"fault unit = {unit}: must be in [0, {mode_array.shape[0] - 1}]")
    if not np.isfinite(magnitude):
        raise ValueError(f"fault magnitude = {magnitude!r}: must be finite")
    mode_array[unit] = FAULT_MODES[mode]
    magnitude_array[unit] = float(magnitude)
