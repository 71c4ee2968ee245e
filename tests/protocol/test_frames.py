"""Tests of protocol/frames.py: ENU/NED, Eq. 2 attitude, MAVLink Euler and quaternion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from pymavlink.quaternion import Quaternion

from protocol import frames as fr

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
# pitch away from the Z-Y-X gimbal lock so Euler angles are unique
tilt = st.floats(-1.5, 1.5, allow_nan=False)
vec3 = hnp.arrays(np.float64, 3, elements=finite)
vecs = hnp.arrays(np.float64, st.tuples(st.integers(0, 20), st.just(3)), elements=finite)


def _angle_close(a: float, b: float, tol: float = 1e-9) -> bool:
    return abs(math.remainder(a - b, 2.0 * math.pi)) < tol


# ----------------------------------------------------------------------------- ENU / NED


def test_enu_ned_known_axes():
    np.testing.assert_array_equal(fr.enu_to_ned([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0])  # east
    np.testing.assert_array_equal(fr.enu_to_ned([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0])  # north
    np.testing.assert_array_equal(fr.enu_to_ned([0.0, 0.0, 8.0]), [0.0, 0.0, -8.0])  # up
    np.testing.assert_array_equal(fr.ned_to_enu([2.0, 3.0, 4.0]), [3.0, 2.0, -4.0])


@given(vec3)
def test_enu_ned_roundtrip_single(v):
    np.testing.assert_array_equal(fr.ned_to_enu(fr.enu_to_ned(v)), v)
    np.testing.assert_array_equal(fr.enu_to_ned(v), fr.T_NED_ENU @ v)


@given(vecs)
def test_enu_ned_roundtrip_batch(v):
    out = fr.enu_to_ned(v)
    assert out.shape == v.shape
    np.testing.assert_array_equal(fr.ned_to_enu(out), v)
    np.testing.assert_array_equal(out, v @ fr.T_NED_ENU.T)


@pytest.mark.parametrize("bad", [[1.0, 2.0], np.zeros((4, 2)), 3.0])
def test_enu_ned_rejects_wrong_shape(bad):
    with pytest.raises(ValueError, match="shape"):
        fr.enu_to_ned(bad)


def test_enu_ned_permutation_is_a_proper_rotation_and_involution():
    np.testing.assert_array_equal(fr.T_NED_ENU @ fr.T_NED_ENU, np.eye(3))
    assert np.linalg.det(fr.T_NED_ENU) == pytest.approx(1.0)
    # T = Rx(pi) Rz(-pi/2), the identity the closed-form Euler map rests on
    np.testing.assert_allclose(fr.T_NED_ENU, fr.rotation_zyx(0, 0, math.pi) @ fr.rotation_zyx(-math.pi / 2, 0, 0), atol=1e-15)


@given(finite)
def test_wrap_pi_range_and_congruence(a):
    w = fr.wrap_pi(a)
    assert isinstance(w, float)
    assert -math.pi <= w <= math.pi
    assert abs(math.remainder(w - a, 2.0 * math.pi)) < 1e-9


# ----------------------------------------------------------------------------- Eq. 2


def test_level_attitude_is_diag_and_points_east():
    r = fr.rwb_from_paper_euler(0.0, 0.0, 0.0)
    np.testing.assert_array_equal(r, np.diag([1.0, -1.0, -1.0]))
    roll, pitch, yaw = fr.mavlink_euler_from_rwb(r)
    assert (roll, pitch) == (0.0, 0.0)
    assert yaw == pytest.approx(math.pi / 2.0)
    # body z (down) is world -Z; body y (right of east) is south
    np.testing.assert_allclose(r[:, 2], [0.0, 0.0, -1.0])
    np.testing.assert_allclose(r[:, 1], [0.0, -1.0, 0.0])


def test_known_yaw_cases():
    # psi = pi/2: body x north -> MAVLink yaw 0; psi = pi: body x west -> yaw -pi/2
    assert fr.mavlink_euler_from_rwb(fr.rwb_from_paper_euler(0, 0, math.pi / 2))[2] == (
        pytest.approx(0.0, abs=1e-12)
    )
    assert fr.mavlink_euler_from_rwb(fr.rwb_from_paper_euler(0, 0, math.pi))[2] == (
        pytest.approx(-math.pi / 2)
    )
    assert fr.paper_euler_to_mavlink(0.0, 0.0, 0.0)[2] == pytest.approx(math.pi / 2)


def test_known_roll_and_pitch_senses():
    # positive phi: right side (y_B) goes down -> MAVLink roll positive
    r = fr.rwb_from_paper_euler(0.2, 0.0, math.pi / 2)
    assert r[2, 1] < 0.0
    assert fr.mavlink_euler_from_rwb(r)[0] == pytest.approx(0.2)
    # negative theta: nose (x_B) goes up -> MAVLink pitch positive (nose up)
    r = fr.rwb_from_paper_euler(0.0, -0.3, math.pi / 2)
    assert r[2, 0] > 0.0
    assert fr.mavlink_euler_from_rwb(r)[1] == pytest.approx(0.3)


@given(angle, tilt, angle)
def test_rwb_is_a_proper_rotation_and_paper_euler_roundtrip(phi, theta, psi):
    r = fr.rwb_from_paper_euler(phi, theta, psi)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
    p2, t2, s2 = fr.paper_euler_from_rwb(r)
    assert _angle_close(p2, phi) and _angle_close(t2, theta) and _angle_close(s2, psi)


# ----------------------------------------------------------------------------- MAVLink Euler


@given(angle, tilt, angle)
def test_r_ned_frd_matches_direct_construction(phi, theta, psi):
    r_wb = fr.rwb_from_paper_euler(phi, theta, psi)
    r_ned = fr.rwb_to_r_ned_frd(r_wb)
    roll, pitch, yaw = fr.paper_euler_to_mavlink(phi, theta, psi)
    np.testing.assert_allclose(r_ned, fr.rotation_zyx(yaw, pitch, roll), atol=1e-12)
    # each body axis, seen in NED, is the ENU body axis permuted
    for k in range(3):
        np.testing.assert_allclose(r_ned[:, k], fr.enu_to_ned(r_wb[:, k]), atol=1e-15)


@given(angle, tilt, angle)
def test_mavlink_euler_from_rwb_agrees_with_closed_form(phi, theta, psi):
    got = fr.mavlink_euler_from_rwb(fr.rwb_from_paper_euler(phi, theta, psi))
    want = fr.paper_euler_to_mavlink(phi, theta, psi)
    for g, w in zip(got, want):
        assert _angle_close(g, w, 1e-8)


@given(angle, tilt, angle)
def test_paper_mavlink_euler_roundtrip(phi, theta, psi):
    back = fr.mavlink_euler_to_paper(*fr.paper_euler_to_mavlink(phi, theta, psi))
    assert back[0] == phi and back[1] == theta
    assert _angle_close(back[2], psi, 1e-12)
    assert all(isinstance(x, float) for x in back)


def test_euler_conversions_accept_arrays():
    phi = np.array([0.1, -0.2])
    roll, pitch, yaw = fr.paper_euler_to_mavlink(phi, np.array([0.3, 0.0]), np.zeros(2))
    np.testing.assert_array_equal(roll, phi)
    np.testing.assert_array_equal(pitch, [-0.3, 0.0])
    np.testing.assert_allclose(yaw, [math.pi / 2] * 2)


# ----------------------------------------------------------------------------- quaternion


@given(angle, tilt, angle)
def test_quaternion_matches_pymavlink_convention(phi, theta, psi):
    r_wb = fr.rwb_from_paper_euler(phi, theta, psi)
    q = fr.mavlink_quaternion_from_rwb(r_wb)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    assert q[0] >= 0.0
    oracle = np.array(Quaternion(list(fr.mavlink_euler_from_rwb(r_wb))).q)
    assert min(np.abs(q - oracle).max(), np.abs(q + oracle).max()) < 1e-9


@given(angle, st.floats(-math.pi / 2, math.pi / 2), angle)
@settings(max_examples=200)
def test_quaternion_reproduces_the_rotation(a, b, c):
    r = fr.rotation_zyx(a, b, c)
    w, x, y, z = fr.quaternion_from_rotation(r)
    r_q = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    np.testing.assert_allclose(r_q, r, atol=1e-12)


@pytest.mark.parametrize(
    "r",
    [np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])],
)
def test_quaternion_of_half_turns(r):
    q = fr.quaternion_from_rotation(r)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    axis = np.argmax(np.abs(q))
    assert abs(q[axis]) == pytest.approx(1.0)


# ----------------------------------------------------------------------------- body rates


@given(vec3)
def test_body_rates_pass_through_unchanged(w):
    np.testing.assert_array_equal(fr.mavlink_body_rates_from_omega_b(w), w)
    np.testing.assert_array_equal(fr.omega_b_from_mavlink_body_rates(w), w)


@given(angle, hnp.arrays(np.float64, 3, elements=st.floats(-2.0, 2.0)))
def test_omega_b_is_mavlink_euler_rate_at_level(yaw_paper, omega_b):
    """At zero roll and pitch, MAVLink Euler rates equal the FRD body rates (p, q, r)."""
    dt = 1e-7
    r0 = fr.rwb_from_paper_euler(0.0, 0.0, yaw_paper)
    wx = np.array([[0, -omega_b[2], omega_b[1]], [omega_b[2], 0, -omega_b[0]], [-omega_b[1], omega_b[0], 0]])
    r1 = r0 @ (np.eye(3) + wx * dt + wx @ wx * dt * dt / 2)  # R' = R [omega_B]x
    e0 = np.array(fr.mavlink_euler_from_rwb(r0))
    e1 = np.array(fr.mavlink_euler_from_rwb(r1))
    rates = np.array([math.remainder(d, 2 * math.pi) for d in e1 - e0]) / dt
    np.testing.assert_allclose(rates, fr.mavlink_body_rates_from_omega_b(omega_b), atol=1e-5)


# ----------------------------------------------------------------------------- quaternion product path


@given(angle, tilt, angle)
def test_mavlink_quaternion_from_quat_wb_matches_matrix_path(phi, theta, psi):
    r_wb = fr.rwb_from_paper_euler(phi, theta, psi)
    q_wb = fr.quaternion_from_rotation(r_wb)
    q = np.array(fr.mavlink_quaternion_from_quat_wb(q_wb))
    expected = fr.mavlink_quaternion_from_rwb(r_wb)
    assert q[0] >= 0.0
    # the same rotation (q and -q are the same when w = 0)
    assert min(np.abs(q - expected).max(), np.abs(q + expected).max()) < 1e-12


def test_mavlink_quaternion_from_quat_wb_level_east():
    """Paper psi = 0 is body x east: MAVLink yaw +90 deg, level."""
    q_wb = fr.quaternion_from_rotation(fr.rwb_from_paper_euler(0.0, 0.0, 0.0))
    roll, pitch, yaw = fr.mavlink_euler_from_quaternion(fr.mavlink_quaternion_from_quat_wb(q_wb))
    assert abs(roll) < 1e-12 and abs(pitch) < 1e-12 and abs(yaw - math.pi / 2) < 1e-12


@settings(max_examples=200, deadline=None)
@given(hnp.arrays(np.float64, st.tuples(st.integers(0, 20), st.just(4)),
                  elements=st.floats(-2.0, 2.0, allow_nan=False)))
def test_quaternion_rows_to_euler_match_the_scalar_conversion(q):
    """The log path (arrays) gives the per-message conversion's angles row by row; no direction: NaN."""
    out = fr.mavlink_euler_from_quaternions(q)
    assert out.shape == (q.shape[0], 3)
    for row, got in zip(q, out):
        try:
            want = fr.mavlink_euler_from_quaternion(row)
        except ValueError:
            assert np.all(np.isnan(got))
            continue
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def test_quaternion_rows_without_direction_are_nan():
    out = fr.mavlink_euler_from_quaternions([[0, 0, 0, 0], [math.nan, 0, 0, 1], [1, 0, 0, 0]])
    assert np.all(np.isnan(out[:2])) and np.allclose(out[2], 0.0)
