"""The IMU half of the firmware chain in one compiled call (paper Sec. 4-1):
calibration -> ensemble of the modules -> complementary filter.

Call from the compiled step loop right after :func:`rig_emulator.sensors.sensor_step.sensors_step`::

    health = attitude_estimation_step(mask, imu_raw, chain, work, att_out)

It does nothing on steps without a fresh gyro/accel sample (``att_out`` keeps the last
estimate). ``att_out`` (6,) = ``phi, theta, psi, wx, wy, wz`` (rad, rad/s). ``health`` is
the bit mask of modules the ensemble currently rejects (0 = all healthy).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.estimation.complementary import CfParams, complementary_state, complementary_step
from rig_emulator.estimation.ensemble import EnsembleParams, ensemble_state, ensemble_step
from rig_emulator.estimation.imu_calibration import ImuCalArrays, apply_imu_calibration
from rig_emulator.sensors.sensor_step import SAMPLED_INERTIAL, SAMPLED_MAG

AttitudeChain = namedtuple("AttitudeChain", ["cal", "ensemble", "cf"])  # ImuCalArrays, EnsembleParams, CfParams
AttitudeWork = namedtuple(
    "AttitudeWork",
    ["si", "combined", "ensemble", "cf_state", "health"],  # (n,3,3), (3,3), EnsembleState, (8,), (1,) int64
)


def make_attitude_chain(cal: ImuCalArrays, ens: EnsembleParams, cf: CfParams,
                        n_modules: int) -> tuple[AttitudeChain, AttitudeWork]:
    """Bundle the parameters and allocate the work arrays once (Python side)."""
    work = AttitudeWork(
        si=np.zeros((n_modules, 3, 3)),
        combined=np.zeros((3, 3)),
        ensemble=ensemble_state(n_modules),
        cf_state=complementary_state(),
        health=np.zeros(1, dtype=np.int64),
    )
    return AttitudeChain(cal, ens, cf), work


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def attitude_estimation_step(sampled_mask, imu_raw, chain, work, att_out):
    """Calibrate, combine and filter the fresh IMU samples; returns the health mask."""
    if sampled_mask & SAMPLED_INERTIAL == 0:
        return work.health[0]
    apply_imu_calibration(imu_raw, chain.cal, work.si, 3 if sampled_mask & SAMPLED_MAG else 2)
    work.health[0] = ensemble_step(work.si, sampled_mask, chain.ensemble, work.ensemble, work.combined)
    complementary_step(work.combined[0], work.combined[1], work.combined[2],
                       sampled_mask & SAMPLED_MAG != 0, chain.cf, work.cf_state, att_out)
    return work.health[0]
