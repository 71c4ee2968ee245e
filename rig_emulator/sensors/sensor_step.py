"""Per physics step: which sensors sample, and sampling them (paper Sec. 4-1 rates).

Sensors run at integer sub-multiples of the physics rate: gyro+accel every
``imu.decim_inertial`` steps, magnetometers every ``imu.decim_mag`` steps, load cells
every ``cells.decim`` steps (defaults 1, 10, 5 at 1 kHz physics). A sensor samples on
steps where ``step_index % decimation == 0``.

Call from the compiled loop, once per physics step after the state update::

    mask = sensors_step(k, q, omega_B, omega_dot_B, thrust_N, rotor_speed_rad_s,
                        suite, state, rng, imu_raw, cell_raw)

``mask`` bits: ``SAMPLED_INERTIAL`` (1) gyro+accel fresh, ``SAMPLED_MAG`` (2) magnetometer
fresh, ``SAMPLED_CELLS`` (4) load cells fresh. ``imu_raw`` is float64 (n_modules, 9),
``cell_raw`` float64 (n_cells,); both hold integer counts and keep their previous values
for sensors that did not sample.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.sensors.imu_module import ImuModulesTruth, _sample_imu_modules
from rig_emulator.sensors.load_cell import LoadCellTruth, sample_load_cells

SAMPLED_INERTIAL = 1
SAMPLED_MAG = 2
SAMPLED_CELLS = 4

SensorSuite = namedtuple("SensorSuite", ["imu", "cells"])
SensorState = namedtuple(
    "SensorState",
    [
        "imu_walk",              # (n_modules, 3, 3) bias random-walk state
        "imu_fault_mode",        # (n_modules,) int64, see rig_emulator.sensors.faults
        "imu_fault_magnitude",   # (n_modules,) float64
        "cell_fault_mode",       # (n_cells,) int64
        "cell_fault_magnitude",  # (n_cells,) float64
        "frame_vibration",       # (6,) gyro (rad/s), accel (m/s^2) every module sees alike
        "motor_field",           # (3,) magnetic field of the motor currents at the modules, B, T
    ],
)


def make_sensor_suite(imu: ImuModulesTruth, cells: LoadCellTruth) -> tuple[SensorSuite, SensorState]:
    """Bundle the drawn kernels and allocate the run-time state (healthy, no drift)."""
    n, c = imu.kernel.n_modules, cells.kernel.n_cells
    state = SensorState(
        imu_walk=np.zeros((n, 3, 3)),
        imu_fault_mode=np.zeros(n, dtype=np.int64),
        imu_fault_magnitude=np.zeros(n),
        cell_fault_mode=np.zeros(c, dtype=np.int64),
        cell_fault_magnitude=np.zeros(c),
        frame_vibration=np.zeros(6),
        motor_field=np.zeros(3),
    )
    return SensorSuite(imu.kernel, cells.kernel), state


def allocate_raw(suite: SensorSuite) -> tuple[np.ndarray, np.ndarray]:
    """The caller-owned raw output arrays: IMU (n_modules, 9) and cells (n_cells,)."""
    return np.zeros((suite.imu.n_modules, 9)), np.zeros(suite.cells.n_cells)


# inlined into the step loop's _sense (its one call site there): a call passes suite and state field by
# field every step (simulation/loop.py)
@jit(inline="always")
def sensors_step(step_index, q, omega_B, omega_dot_B, thrust_N, rotor_speed_rad_s, suite, state, rng,
                 imu_raw_out, cell_raw_out):
    """Sample whatever is due at ``step_index``; returns the bit mask of fresh sensors."""
    imu = suite.imu
    do_inertial = step_index % imu.decim_inertial == 0
    do_mag = step_index % imu.decim_mag == 0
    mask = 0
    if do_inertial or do_mag:
        # the variant without reference counting: this runs on every step loop sample
        _sample_imu_modules(q, omega_B, omega_dot_B, state.frame_vibration, state.motor_field, do_inertial, do_mag, imu,
                            state.imu_walk,
                            state.imu_fault_mode, state.imu_fault_magnitude, rng, imu_raw_out)
        if do_inertial:
            mask |= SAMPLED_INERTIAL
        if do_mag:
            mask |= SAMPLED_MAG
    if step_index % suite.cells.decim == 0:
        sample_load_cells(thrust_N, rotor_speed_rad_s, suite.cells, state.cell_fault_mode,
                          state.cell_fault_magnitude, rng, cell_raw_out)
        mask |= SAMPLED_CELLS
    return mask
