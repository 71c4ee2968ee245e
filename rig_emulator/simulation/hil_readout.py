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

from typing import NamedTuple

from rig_emulator.physics import state as S
from rig_emulator.sensors.barometer import KELVIN_AT_0C, isa_altitude, isa_pressure_temperature

_QUAT, _VEL, _POS, _OMEGA = S.QUAT, S.VEL, S.POS, S.OMEGA


class HilReadout(NamedTuple):
    """One step's sensor readings and truth (SI; world ENU, body FRD). Immutable; a named
    tuple rather than a frozen dataclass: one is made at every flight-stack step, and a
    frozen dataclass sets each of its fourteen fields through ``object.__setattr__``."""

    time_s: float
    gyro: tuple  # (3,) rad/s
    accel: tuple  # (3,) m/s^2, specific force including the virtual translation
    mag: tuple  # (3,) T
    imu_sampled: bool
    mag_sampled: bool
    pressure_pa: float
    temperature_c: float
    baro_altitude_m: float  # altitude above mean sea level of the pressure read (ISA)
    position: tuple  # (3,) m, virtual, ENU about the local origin
    velocity: tuple  # (3,) m/s
    acceleration: tuple  # (3,) m/s^2, mean over the step
    quaternion: tuple  # (4,) (w, x, y, z) of R_WB, true
    body_rates: tuple  # (3,) rad/s, true omega_B


def sampled_between(k0: int, k1: int, decimation: int) -> bool:
    """Whether a sensor sampling every ``decimation`` physics steps sampled at one of the
    steps ``k0 .. k1 - 1`` (the loop samples at the start of step k when k % decimation == 0)."""
    if k1 <= k0:
        return False
    first = -(-k0 // decimation) * decimation  # the first multiple >= k0
    return first < k1


def _body_from_world(q, v):
    """``R_WB^T v`` for the quaternion ``q`` (w, x, y, z) of R_WB, in plain floats."""
    q0, q1, q2, q3 = q
    a0, a1, a2 = v
    return (
        (1.0 - 2.0 * (q2 * q2 + q3 * q3)) * a0 + 2.0 * (q1 * q2 + q0 * q3) * a1 + 2.0 * (q1 * q3 - q0 * q2) * a2,
        2.0 * (q1 * q2 - q0 * q3) * a0 + (1.0 - 2.0 * (q1 * q1 + q3 * q3)) * a1 + 2.0 * (q2 * q3 + q0 * q1) * a2,
        2.0 * (q1 * q3 + q0 * q2) * a0 + 2.0 * (q2 * q3 - q0 * q1) * a1 + (1.0 - 2.0 * (q1 * q1 + q2 * q2)) * a2,
    )


def hil_readout(sim, k_prev: int, velocity_prev: tuple, home_alt_m: float) -> HilReadout:
    """The readout after the steps ``k_prev .. sim.k - 1`` (``velocity_prev``: the virtual
    velocity at step ``k_prev``). Plain floats (tuples): it runs at every flight-stack step."""
    x = sim.x.tolist()
    q = tuple(x[_QUAT:_QUAT + 4])
    velocity = tuple(x[_VEL:_VEL + 3])
    k = sim.k
    dt = sim.dt
    period = (k - k_prev) * dt
    if period > 0.0:
        v0, v1, v2 = velocity_prev
        accel_w = ((velocity[0] - v0) / period, (velocity[1] - v1) / period, (velocity[2] - v2) / period)
    else:
        accel_w = (0.0, 0.0, 0.0)
    sp = sim.sensing.params
    if sp.simulate:
        gyro, f_modules, mag = sim.sensing.state.awork.combined.tolist()
        gyro, mag = tuple(gyro), tuple(mag)
        imu = sp.suite.imu
        imu_new = sampled_between(k_prev, k, imu.decim_inertial)
        mag_new = sampled_between(k_prev, k, imu.decim_mag)
    else:
        gyro = tuple(x[_OMEGA:_OMEGA + 3])
        f_modules = _body_from_world(q, (0.0, 0.0, sim.pp.g))
        mag = _body_from_world(q, sp.suite.imu.earth_field_W.tolist())
        imu_new = mag_new = k > k_prev
    a_body = _body_from_world(q, accel_w)
    pressure, temperature_k = isa_pressure_temperature(home_alt_m + x[_POS + 2])
    return HilReadout(
        k * dt,  # time_s
        gyro,
        (f_modules[0] + a_body[0], f_modules[1] + a_body[1], f_modules[2] + a_body[2]),  # accel
        mag,
        bool(imu_new),  # imu_sampled
        bool(mag_new),  # mag_sampled
        pressure,  # pressure_pa
        temperature_k - KELVIN_AT_0C,  # temperature_c
        isa_altitude(pressure),  # baro_altitude_m
        tuple(x[_POS:_POS + 3]),  # position
        velocity,
        accel_w,  # acceleration
        q,  # quaternion
        tuple(x[_OMEGA:_OMEGA + 3]),  # body_rates
    )
