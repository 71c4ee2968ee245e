"""Complementary attitude filter giving the paper's Euler angles (Sec. 4-1, Eq. 2, A2).

Angles are the Z-Y-X angles ``(phi, theta, psi)`` of ``Q = R_WB diag(1,-1,-1)``.
Per IMU sample (period ``dt_s``):

1. Accelerometer low-pass (first order, ``accel_lowpass_hz``): the paper's filter that
   removes dynamic accelerations before the tilt is taken.
2. Gyro propagation through the Euler-rate kinematics (``euler_rates_from_body_rates``).
3. Tilt correction: at rest ``f_B = R_WB^T [0,0,g] = g [-sin(theta), -sin(phi) cos(theta),
   -cos(phi) cos(theta)]`` (B = FRD), so ``phi_a = atan2(-f_y, -f_z)`` and
   ``theta_a = atan2(-f_x, sqrt(f_y^2 + f_z^2))``; the angles move toward them by
   ``dt / tau_roll_pitch_s`` of the (wrapped) difference. Reading: the correction is
   skipped while ``| |f_lp| - g |`` exceeds ``accel_gate_m_s2`` (not quasi-static).
4. Heading correction on each fresh magnetometer sample: the field in FLU axes
   ``diag(1,-1,-1) m_B`` is levelled with the estimated roll and pitch,
   ``h = Ry(theta) Rx(phi) m_FLU = Rz(psi)^T m_W``, so ``psi_m = alpha - atan2(h_y, h_x)``
   with ``alpha = 90 deg - declination`` the direction of magnetic north from east (ENU);
   ``psi`` moves toward it by ``dt_mag / tau_yaw_s`` of the wrapped difference.

``phi`` and ``psi`` are wrapped to (-pi, pi]; ``theta`` is kept within +-89.9 deg (the
Euler-rate kinematics are singular at +-90 deg). The first sample initialises the angles
from the accelerometer (and the first magnetometer sample the heading).
Output ``out`` (6,): ``phi, theta, psi`` [rad] and ``omega_B`` [rad/s], the calibrated
gyro ensemble (its biases were removed by calibration).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.physics.rotation import euler_rates_from_body_rates

CfParams = namedtuple(
    "CfParams",
    ["dt_s", "k_tilt", "k_yaw", "acc_alpha", "gate_m_s2", "gravity_m_s2", "heading_ref_rad"],
)
CF_STATE_SIZE = 8  # phi, theta, psi, f_lp x/y/z, initialised, heading initialised
THETA_LIMIT = math.radians(89.9)


def complementary_params(est_cfg: dict, imu_dt_s: float, mag_dt_s: float, gravity_m_s2: float) -> CfParams:
    """Compiled-side parameters from the ``complementary`` table and the sample periods."""
    c = est_cfg["complementary"]
    return CfParams(
        dt_s=float(imu_dt_s),
        k_tilt=min(1.0, imu_dt_s / c["tau_roll_pitch_s"]),
        k_yaw=min(1.0, mag_dt_s / c["tau_yaw_s"]),
        acc_alpha=1.0 - math.exp(-2.0 * math.pi * c["accel_lowpass_hz"] * imu_dt_s),
        gate_m_s2=c["accel_gate_m_s2"],
        gravity_m_s2=float(gravity_m_s2),
        heading_ref_rad=math.radians(90.0 - c["declination_deg"]),
    )


def complementary_state() -> np.ndarray:
    return np.zeros(CF_STATE_SIZE)


@jit(inline="always")
def wrap_pi(a):
    """Wrap an angle to (-pi, pi]."""
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


@jit(inline="always")
def tilt_from_specific_force(fx, fy, fz):
    """(phi, theta) of a quasi-static specific force ``f_B`` (B = FRD)."""
    return math.atan2(-fy, -fz), math.atan2(-fx, math.sqrt(fy * fy + fz * fz))


@jit(inline="always")
def heading_from_mag(mx, my, mz, phi, theta, heading_ref):
    """Tilt-compensated heading ``psi`` of a body-frame (FRD) field for given roll and pitch."""
    ux = mx
    uy = -my  # FLU axes
    uz = -mz
    cph = math.cos(phi)
    sph = math.sin(phi)
    v1 = uy * cph - uz * sph
    v2 = uy * sph + uz * cph
    hx = math.cos(theta) * ux + math.sin(theta) * v2
    return wrap_pi(heading_ref - math.atan2(v1, hx))


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def complementary_step(gyro, accel, mag, mag_fresh, p, state, out):
    """One IMU sample of the filter; writes ``out = [phi, theta, psi, wx, wy, wz]``."""
    if state[6] == 0.0:
        state[3] = accel[0]
        state[4] = accel[1]
        state[5] = accel[2]
        phi, theta = tilt_from_specific_force(accel[0], accel[1], accel[2])
        state[0] = phi
        state[1] = theta
        state[2] = 0.0
        state[6] = 1.0
    else:
        a = p.acc_alpha
        state[3] += a * (accel[0] - state[3])
        state[4] += a * (accel[1] - state[4])
        state[5] += a * (accel[2] - state[5])
        phi = state[0]
        theta = state[1]
        dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, gyro[0], gyro[1], gyro[2])
        phi += p.dt_s * dphi
        theta += p.dt_s * dtheta
        psi = state[2] + p.dt_s * dpsi
        fx = state[3]
        fy = state[4]
        fz = state[5]
        fn = math.sqrt(fx * fx + fy * fy + fz * fz)
        if abs(fn - p.gravity_m_s2) < p.gate_m_s2:
            phi_a, theta_a = tilt_from_specific_force(fx, fy, fz)
            phi += p.k_tilt * wrap_pi(phi_a - phi)
            theta += p.k_tilt * (theta_a - theta)
        if theta > THETA_LIMIT:
            theta = THETA_LIMIT
        elif theta < -THETA_LIMIT:
            theta = -THETA_LIMIT
        state[0] = wrap_pi(phi)
        state[1] = theta
        state[2] = wrap_pi(psi)
    if mag_fresh:
        psi_m = heading_from_mag(mag[0], mag[1], mag[2], state[0], state[1], p.heading_ref_rad)
        if state[7] == 0.0:
            state[2] = psi_m
            state[7] = 1.0
        else:
            state[2] = wrap_pi(state[2] + p.k_yaw * wrap_pi(psi_m - state[2]))
    out[0] = state[0]
    out[1] = state[1]
    out[2] = state[2]
    out[3] = gyro[0]
    out[4] = gyro[1]
    out[5] = gyro[2]
