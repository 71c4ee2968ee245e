"""Complementary filter (paper Sec. 4-1): tilt and heading geometry, and a comparison with
the ``ahrs`` package's complementary filter on the same samples.

ahrs (0.4) conventions, converted explicitly here: it expects body axes with z up at rest
(its roll is ``atan2(a_y, a_z)`` of a specific force reading ``+g`` on z when level), i.e.
FLU: ``x_FLU = diag(1,-1,-1) x_FRD`` for gyro, accelerometer and magnetometer. Its angles
are then the Z-Y-X angles of ``Q = R_WB diag(1,-1,-1)`` with yaw measured from magnetic
north along its x axis, so ``psi = psi_ahrs + alpha`` with ``alpha = 90 deg - declination``
(the ENU direction of magnetic north). Its gain is the weight of the gyro path per sample:
``gain = 1 - dt / tau``. It integrates body rates as if they were Euler rates and does not
low-pass the accelerometer.
"""

import math

import numpy as np
from ahrs.filters import Complementary
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.estimation.complementary import (
    complementary_params, complementary_state, complementary_step, heading_from_mag, tilt_from_specific_force)
from rig_emulator.estimation.estimation_config import load_estimation_config
from rig_emulator.physics.rotation import rwb_from_euler
from rig_emulator.sensors.imu_module import earth_field_enu, load_imu_config

SITE = load_imu_config()["imu_array"]["site"]
M_W = earth_field_enu(SITE)
ALPHA = math.radians(90.0 - SITE["declination_deg"])


@settings(max_examples=100, deadline=None)
@given(st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1))
def test_tilt_and_heading_invert_eq2(phi, theta, psi):
    R = rwb_from_euler(phi, theta, psi)
    f = R.T @ np.array([0.0, 0.0, 9.81])
    assert np.allclose(f, 9.81 * np.array([-math.sin(theta), -math.sin(phi) * math.cos(theta),
                                           -math.cos(phi) * math.cos(theta)]), atol=1e-12)
    p, t = tilt_from_specific_force(*f)
    assert abs(math.remainder(p - phi, 2 * math.pi)) < 1e-9 and abs(t - theta) < 1e-9
    m = R.T @ M_W
    assert abs(math.remainder(heading_from_mag(*m, phi, theta, ALPHA) - psi, 2 * math.pi)) < 1e-9


def _trajectory(n, dt, amp, w, psi0):
    t = np.arange(n) * dt
    phi = amp[0] * np.sin(w * t)
    theta = amp[1] * np.sin(w * t + 1.0)
    psi = psi0 + amp[2] * np.sin(0.5 * w * t + 2.0)
    dphi, dtheta, dpsi = amp[0] * w * np.cos(w * t), amp[1] * w * np.cos(w * t + 1.0), amp[2] * 0.5 * w * np.cos(0.5 * w * t + 2.0)
    p = dphi - np.sin(theta) * dpsi
    q = np.cos(phi) * dtheta + np.sin(phi) * np.cos(theta) * dpsi
    r = -np.sin(phi) * dtheta + np.cos(phi) * np.cos(theta) * dpsi
    omega = np.stack([p, -q, -r], 1)
    f = np.zeros((n, 3))
    m = np.zeros((n, 3))
    for k in range(n):
        R = rwb_from_euler(phi[k], theta[k], psi[k])
        f[k] = R.T @ np.array([0.0, 0.0, 9.81])
        m[k] = R.T @ M_W
    return np.stack([phi, theta, psi], 1), omega, f, m


def test_wrapping_through_180_deg_heading():
    est = load_estimation_config()
    p = complementary_params(est, 1e-3, 1e-2, 9.81)
    st_ = complementary_state()
    out = np.zeros(6)
    n = 4000
    truth, omega, f, m = _trajectory(n, 1e-3, (0.0, 0.0, 0.0), 0.0, math.radians(170.0))
    omega[:, 2] = -math.radians(20.0)  # yaw rate +20 deg/s (FRD z down)
    psi = math.radians(170.0) + math.radians(20.0) * np.arange(n) * 1e-3
    for k in range(n):
        R = rwb_from_euler(0.0, 0.0, psi[k])
        complementary_step(omega[k], f[k], R.T @ M_W, k % 10 == 0, p, st_, out)
        assert -math.pi < out[2] <= math.pi
    assert abs(math.remainder(out[2] - psi[-1], 2 * math.pi)) < math.radians(0.2)


def test_more_accurate_than_ahrs_on_a_dynamic_trajectory():
    dt, n = 1e-3, 30000
    amp = np.radians([25.0, 20.0, 40.0])
    truth, omega, f, m = _trajectory(n, dt, amp, 0.8, math.radians(20.0))
    rng = np.random.default_rng(3)
    # ensemble-level noise of five calibrated modules
    gyro = omega + rng.normal(0, math.radians(0.08) / math.sqrt(5), (n, 3))
    acc = f + rng.normal(0, 0.0063 * 9.81 / math.sqrt(5), (n, 3))
    mag = m + rng.normal(0, 2e-7 / math.sqrt(5), (n, 3))
    mag_held = mag.copy()
    for k in range(n):
        if k % 10:
            mag_held[k] = mag_held[k - 1]
    est = load_estimation_config()
    tau = est["complementary"]["tau_roll_pitch_s"]
    p = complementary_params(est, dt, 10 * dt, 9.81)
    st_ = complementary_state()
    out = np.zeros(6)
    ours = np.zeros((n, 3))
    for k in range(n):
        complementary_step(gyro[k], acc[k], mag_held[k], k % 10 == 0, p, st_, out)
        ours[k] = out[:3]
    flu = np.array([1.0, -1.0, -1.0])
    ref = Complementary(gyr=gyro * flu, acc=acc * flu, mag=mag_held * flu * 1e6, Dt=dt, gain=1.0 - dt / tau)
    theirs = ref.W.copy()
    theirs[:, 2] += ALPHA
    s = 5000
    wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
    e_ours = np.degrees(np.sqrt(np.mean(wrap(ours[s:] - truth[s:]) ** 2, axis=0)))
    e_theirs = np.degrees(np.sqrt(np.mean(wrap(theirs[s:] - truth[s:]) ** 2, axis=0)))
    diff = np.degrees(np.sqrt(np.mean(wrap(ours[s:] - theirs[s:]) ** 2, axis=0)))
    print(f"\nrms error vs truth [deg] ours {e_ours}, ahrs {e_theirs}; rms difference {diff}")
    assert np.all(e_ours <= e_theirs * 1.0 + 0.02)
    assert e_ours.max() < 1.0
