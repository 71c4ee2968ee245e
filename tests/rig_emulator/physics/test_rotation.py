"""Eq. 2 rotation matrix, quaternion round trips, Euler-rate kinematics."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.physics.rotation import (
    euler_from_quat,
    euler_rates_from_body_rates,
    quat_derivative,
    quat_from_euler,
    quat_to_rot,
    rwb_from_euler,
)

angle = st.floats(-math.pi + 1e-6, math.pi - 1e-6)
tilt = st.floats(-1.4, 1.4)


def _rot(phi, theta, psi):
    q = np.zeros(4)
    quat_from_euler(phi, theta, psi, q)
    R = np.zeros((3, 3))
    quat_to_rot(q[0], q[1], q[2], q[3], R)
    return q, R


def test_eq2_level_is_diag_flip():
    _, R = _rot(0.0, 0.0, 0.0)
    assert np.allclose(R, np.diag([1.0, -1.0, -1.0]), atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(angle, tilt, angle)
def test_quaternion_matches_eq2_and_round_trips(phi, theta, psi):
    q, R = _rot(phi, theta, psi)
    assert np.allclose(R, rwb_from_euler(phi, theta, psi), atol=1e-12)
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert abs(np.linalg.det(R) - 1.0) < 1e-12
    out = euler_from_quat(q[0], q[1], q[2], q[3])
    assert np.allclose(out, (phi, theta, psi), atol=1e-9)


@settings(max_examples=100, deadline=None)
@given(angle, tilt, angle, st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3))
def test_quaternion_kinematics_is_body_rate(phi, theta, psi, wx, wy, wz):
    """q' from quat_derivative gives R' = R [omega_B]x."""
    q, R = _rot(phi, theta, psi)
    dq = np.zeros(4)
    quat_derivative(q[0], q[1], q[2], q[3], wx, wy, wz, dq)
    h = 1e-7
    qp = q + h * dq
    Rp = np.zeros((3, 3))
    quat_to_rot(qp[0], qp[1], qp[2], qp[3], Rp)
    skew = np.array([[0, -wz, wy], [wz, 0, -wx], [-wy, wx, 0]])
    assert np.allclose((Rp - R) / h, R @ skew, atol=1e-5)


@settings(max_examples=100, deadline=None)
@given(angle, tilt, angle, st.floats(-2, 2), st.floats(-2, 2), st.floats(-2, 2))
def test_euler_rates_match_finite_difference(phi, theta, psi, wx, wy, wz):
    q, _ = _rot(phi, theta, psi)
    dq = np.zeros(4)
    quat_derivative(q[0], q[1], q[2], q[3], wx, wy, wz, dq)
    h = 1e-7
    qp = q + h * dq
    qp /= np.linalg.norm(qp)
    e0 = np.array(euler_from_quat(*q))
    e1 = np.array(euler_from_quat(*qp))
    d = (e1 - e0 + math.pi) % (2 * math.pi) - math.pi
    rates = np.array(euler_rates_from_body_rates(phi, theta, wx, wy, wz))
    assert np.allclose(d / h, rates, atol=2e-4 * (1 + np.abs(rates).max()))


def test_positive_torque_about_y_body_lowers_theta():
    """The Reading in CONVENTIONS: B = FRD, so +omega_y_B decreases theta."""
    rates = euler_rates_from_body_rates(0.0, 0.0, 0.0, 1.0, 0.0)
    assert rates[1] == -1.0
