"""What the rig gives a flight stack in the loop at the end of one of its steps (SI, ENU/FRD).

A flight stack (PX4's Simulator MAVLink API, :mod:`rig_emulator.link.px4_simulator`) sees the
rig as a vehicle that flies: its inertial sensors are the rig's emulated IMU modules, its
position sensors follow the virtual translation of Eq. 1. :func:`hil_readout` reads one
:class:`HilReadout` from a :class:`~rig_emulator.simulation.run.Simulation`; the link layer
only converts it to MAVLink units and frames.

* **gyro, magnetometer**: the ensemble of the five calibrated IMU modules (Sec. 4-1: the
  rig's own calibration applied to the raw counts, then the ensemble), body FRD, rad/s and T.
  With ``sensors.simulate = false`` the true body rates and the ideal field ``R_WB^T m_W``.
* **accelerometer**: the same ensemble plus the virtual translation's acceleration
  expressed in the body, ``f = f_modules + R_WB^T a_virtual``. Reading: the modules on the
  joint measure ``R_WB^T [0, 0, g]`` (the rig does not translate); a vehicle flying the
  virtual trajectory would measure ``R_WB^T (a_virtual + [0, 0, g])``. Without the added term
  the flight stack's estimator would see GPS and barometer accelerate while its
  accelerometer says the vehicle is still, and reject one or the other. ``a_virtual`` is the
  mean acceleration of the virtual velocity over the step (``(v_k - v_{k-1}) / T``), so it
  integrates exactly to the velocity the GPS reports.
* **position, velocity** (GPS, barometer, ground truth): the plant's virtual translation
  (Eq. 1 integrated with the motors' true thrusts and the true attitude), world ENU. The
  rig's own onboard estimate of it is not used: the flight stack estimates for itself.
* **barometer**: :func:`rig_emulator.sensors.barometer.isa_pressure_temperature` at the home
  altitude plus the virtual height.
* **truth**: attitude quaternion of ``R_WB`` and body rates from the physics state.

``imu_sampled`` / ``mag_sampled`` say whether the modules took a new gyro/accelerometer or
magnetometer sample during the step (sensor rates of ``imu_array.toml``: 500 Hz and 100 Hz
at the default 1 kHz physics), so the flight stack is told which readings are new.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rig_emulator.physics import state as S
from rig_emulator.physics.rotation import quat_to_rot
from rig_emulator.sensors.barometer import KELVIN_AT_0C, isa_altitude, isa_pressure_temperature


@dataclass(frozen=True)
class HilReadout:
    """One step's sensor readings and truth (SI; world ENU, body FRD)."""

    time_s: float
    gyro: np.ndarray  # (3,) rad/s
    accel: np.ndarray  # (3,) m/s^2, specific force including the virtual translation
    mag: np.ndarray  # (3,) T
    imu_sampled: bool
    mag_sampled: bool
    pressure_pa: float
    temperature_c: float
    baro_altitude_m: float  # altitude above mean sea level of the pressure read (ISA)
    position: np.ndarray  # (3,) m, virtual, ENU about the local origin
    velocity: np.ndarray  # (3,) m/s
    acceleration: np.ndarray  # (3,) m/s^2, mean over the step
    quaternion: np.ndarray  # (4,) (w, x, y, z) of R_WB, true
    body_rates: np.ndarray  # (3,) rad/s, true omega_B


def sampled_between(k0: int, k1: int, decimation: int) -> bool:
    """Whether a sensor sampling every ``decimation`` physics steps sampled at one of the
    steps ``k0 .. k1 - 1`` (the loop samples at the start of step k when k % decimation == 0)."""
    if k1 <= k0:
        return False
    first = -(-k0 // decimation) * decimation  # the first multiple >= k0
    return first < k1


def hil_readout(sim, k_prev: int, velocity_prev: np.ndarray, home_alt_m: float) -> HilReadout:
    """The readout after the steps ``k_prev .. sim.k - 1`` (``velocity_prev``: the virtual
    velocity at step ``k_prev``)."""
    x = sim.x
    R = np.empty((3, 3))
    quat_to_rot(x[S.QUAT], x[S.QUAT + 1], x[S.QUAT + 2], x[S.QUAT + 3], R)
    velocity = x[S.VEL:S.VEL + 3].copy()
    period = (sim.k - k_prev) * sim.dt
    accel_w = (velocity - velocity_prev) / period if period > 0.0 else np.zeros(3)
    sp, ss = sim.sensing.params, sim.sensing.state
    if sp.simulate:
        fused = ss.awork.combined  # [gyro, accel, mag] x axis, calibrated ensemble
        gyro, f_modules, mag = fused[0].copy(), fused[1].copy(), fused[2].copy()
        imu = sp.suite.imu
        imu_new = sampled_between(k_prev, sim.k, imu.decim_inertial)
        mag_new = sampled_between(k_prev, sim.k, imu.decim_mag)
    else:
        gyro = x[S.OMEGA:S.OMEGA + 3].copy()
        f_modules = R.T @ np.array([0.0, 0.0, sim.pp.g])
        mag = R.T @ sim.sensing.params.suite.imu.earth_field_W
        imu_new = mag_new = sim.k > k_prev
    altitude = home_alt_m + float(x[S.POS + 2])
    pressure, temperature_k = isa_pressure_temperature(altitude)
    return HilReadout(
        time_s=sim.k * sim.dt,
        gyro=gyro,
        accel=f_modules + R.T @ accel_w,
        mag=mag,
        imu_sampled=bool(imu_new),
        mag_sampled=bool(mag_new),
        pressure_pa=pressure,
        temperature_c=temperature_k - KELVIN_AT_0C,
        baro_altitude_m=isa_altitude(pressure),
        position=x[S.POS:S.POS + 3].copy(),
        velocity=velocity,
        acceleration=accel_w,
        quaternion=x[S.QUAT:S.QUAT + 4].copy(),
        body_rates=x[S.OMEGA:S.OMEGA + 3].copy(),
    )
