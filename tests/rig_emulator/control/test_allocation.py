"""A6 inverted: exact round trip inside the limits; when saturating, attitude authority kept first
(priority "attitude"), the collective u1 kept first (priority "thrust", the hilms rig) or each motor
clipped on its own (priority "clip", no priority)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import pytest

from rig_emulator.control.allocation import (
    PRIORITIES,
    PRIORITY_ATTITUDE,
    PRIORITY_CLIP,
    PRIORITY_THRUST,
    SATURATED_COLLECTIVE,
    SATURATED_ROLL_PITCH,
    SATURATED_YAW,
    allocate,
    euler_torque_to_body,
    thrust_first_scale,
)

L, C, FMAX = 0.28, 0.016, 7.0


def _a6(f):
    return f.sum(), L * (f[3] - f[1]), L * (f[0] - f[2]), C * (f[0] - f[1] + f[2] - f[3])


@pytest.mark.parametrize("priority", sorted(PRIORITIES))
@settings(max_examples=300, deadline=None)
@given(forces=st.lists(st.floats(0.0, FMAX), min_size=4, max_size=4))
def test_round_trip_inside_limits(priority, forces):
    f = np.array(forces)
    out = np.zeros(4)
    flags = allocate(*_a6(f), L, C, FMAX, PRIORITIES[priority], out)
    assert flags == 0
    assert np.allclose(out, f, atol=1e-9)


@settings(max_examples=300, deadline=None)
@given(st.floats(-50, 80), st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 1))
def test_outputs_always_within_limits(u1, u2, u3, u4):
    out = np.zeros(4)
    allocate(u1, u2, u3, u4, L, C, FMAX, PRIORITY_ATTITUDE, out)
    assert np.all(out >= 0.0) and np.all(out <= FMAX)


@settings(max_examples=200, deadline=None)
@given(st.floats(0, 40), st.floats(-0.9, 0.9), st.floats(-0.9, 0.9), st.floats(-0.5, 0.5))
def test_roll_pitch_kept_when_only_collective_or_yaw_saturate(u1, u2, u3, u4):
    out = np.zeros(4)
    flags = allocate(u1, u2, u3, u4, L, C, FMAX, PRIORITY_ATTITUDE, out)
    if not flags & SATURATED_ROLL_PITCH:
        _, a2, a3, _ = _a6(out)
        assert abs(a2 - u2) < 1e-9 and abs(a3 - u3) < 1e-9


def test_collective_gives_way_to_roll():
    out = np.zeros(4)
    flags = allocate(4 * FMAX, 0.5, 0.0, 0.0, L, C, FMAX, PRIORITY_ATTITUDE, out)
    assert flags & SATURATED_COLLECTIVE and not flags & SATURATED_ROLL_PITCH
    assert abs(_a6(out)[1] - 0.5) < 1e-12


@pytest.mark.parametrize("priority", [PRIORITY_ATTITUDE, PRIORITY_THRUST], ids=["attitude", "thrust"])
def test_yaw_is_last(priority):
    out = np.zeros(4)
    flags = allocate(4 * 5.5, 0.0, 0.0, 1.0, L, C, FMAX, priority, out)
    assert flags & SATURATED_YAW
    u1, u2, u3, u4 = _a6(out)
    assert abs(u1 - 22.0) < 1e-9 and abs(u2) < 1e-12 and abs(u3) < 1e-12 and 0 < u4 < 1.0


def test_euler_to_body_flip():
    assert euler_torque_to_body(1.0, 2.0, 3.0) == (1.0, -2.0, -3.0)


# --- priority "thrust" (control.allocation_priority, the hilms rig) -------------------------------

HOVER = 2.23 * 9.81  # N, Table 2's mass


@settings(max_examples=300, deadline=None)
@given(st.floats(-50, 80), st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 1))
def test_thrust_first_keeps_u1_and_the_torque_direction(u1, u2, u3, u4):
    out = np.zeros(4)
    flags = allocate(u1, u2, u3, u4, L, C, FMAX, PRIORITY_THRUST, out)
    assert np.all(out >= 0.0) and np.all(out <= FMAX)
    a1, a2, a3, _ = _a6(out)
    tol = 4e-9 * FMAX + 1e-9  # the exact inverse is taken within 1e-9 f_max per motor (rounding)
    assert abs(a1 - min(max(u1, 0.0), 4 * FMAX)) < tol  # u1 as asked, within what four motors give
    # roll/pitch: the same direction, scaled by one factor in [0, 1]
    assert a2 * u2 >= -1e-12 and a3 * u3 >= -1e-12
    assert abs(a2) <= abs(u2) + tol and abs(a3) <= abs(u3) + tol
    assert abs(a2 * u3 - a3 * u2) < tol
    if not flags & SATURATED_ROLL_PITCH:
        assert abs(a2 - u2) < tol and abs(a3 - u3) < tol


def test_saturated_pitch_at_hover_sign_and_size():
    """Table 3's saturated FLC pitch torque (3 d1_u3 = 1.68 N m) at hover: 'attitude' keeps the torque
    and lowers u1 to 4 (f_max - 3 N) = 16.0 N; 'thrust' keeps u1 = m g and scales the torque by
    (f_max - m g / 4) / 3 N = 0.51."""
    u3 = 3 * 0.56
    att, thr = np.zeros(4), np.zeros(4)
    f_att = allocate(HOVER, 0.0, u3, 0.0, L, C, FMAX, PRIORITY_ATTITUDE, att)
    f_thr = allocate(HOVER, 0.0, u3, 0.0, L, C, FMAX, PRIORITY_THRUST, thr)
    u1a, _, u3a, _ = _a6(att)
    u1t, _, u3t, _ = _a6(thr)
    assert f_att & SATURATED_COLLECTIVE and not f_att & SATURATED_ROLL_PITCH
    assert abs(u3a - u3) < 1e-12 and abs(u1a - 4 * (FMAX - u3 / (2 * L))) < 1e-9  # 16.0 N
    assert 15.9 < u1a < 16.1
    assert f_thr & SATURATED_ROLL_PITCH and not f_thr & SATURATED_COLLECTIVE
    assert abs(u1t - HOVER) < 1e-9
    scale = (FMAX - HOVER / 4) / (u3 / (2 * L))
    assert abs(u3t - scale * u3) < 1e-9 and 0.50 < scale < 0.52  # 0.86 N m
    assert thr[0] == FMAX and abs(thr[2] - (HOVER / 2 - FMAX)) < 1e-9  # motor 1 at its ceiling, motor 3 below hover


def test_saturated_pitch_at_hover_clip_sign_and_size():
    """The same request with each motor clipped on its own (priority "clip"): motor 1 asks
    m g / 4 + 3.0 N = 8.47 N and gets f_max = 7.00 N, motor 3 gets its 2.47 N. Only the overflow
    (1.47 N) is lost, from the collective AND the torque: u1 = m g - 1.47 N = 20.4 N (attitude: 16.0 N,
    thrust: 21.9 N), u3 = l (7.00 - 2.47) N = 1.27 N m, 0.76 of the 1.68 N m asked (attitude 1.00,
    thrust 0.51); the clipped motor 1 also leaves a yaw torque -c 1.47 N the mixer did not ask."""
    u3 = 3 * 0.56
    out = np.zeros(4)
    flags = allocate(HOVER, 0.0, u3, 0.0, L, C, FMAX, PRIORITY_CLIP, out)
    assert flags == SATURATED_COLLECTIVE | SATURATED_ROLL_PITCH | SATURATED_YAW
    over = HOVER / 4 + u3 / (2 * L) - FMAX  # 1.47 N over motor 1's ceiling
    assert 1.46 < over < 1.48
    assert out[0] == FMAX and abs(out[2] - (HOVER / 4 - u3 / (2 * L))) < 1e-12
    assert out[1] == out[3] == HOVER / 4
    a1, a2, a3, a4 = _a6(out)
    assert abs(a1 - (HOVER - over)) < 1e-9 and 20.3 < a1 < 20.5          # between 16.0 (attitude) and 21.9 (thrust)
    assert abs(a3 - (u3 - L * over)) < 1e-9 and 0.75 < a3 / u3 < 0.77    # between 0.51 (thrust) and 1 (attitude)
    assert a2 == 0.0 and abs(a4 + C * over) < 1e-12                       # an unasked yaw torque, opposite sign


@settings(max_examples=300, deadline=None)
@given(st.floats(-50, 80), st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 1))
def test_clip_is_the_exact_inverse_clipped_motor_by_motor(u1, u2, u3, u4):
    out = np.zeros(4)
    flags = allocate(u1, u2, u3, u4, L, C, FMAX, PRIORITY_CLIP, out)
    a = u3 / (2 * L)
    b = u2 / (2 * L)
    y = u4 / (4 * C)
    exact = np.array([u1 / 4 + a + y, u1 / 4 - b - y, u1 / 4 - a + y, u1 / 4 + b - y])
    assert np.allclose(out, np.clip(exact, 0.0, FMAX), atol=1e-12)
    if flags == 0:
        assert np.allclose(out, exact, atol=4e-9 * FMAX)


def test_thrust_first_scale_sign_and_size():
    assert thrust_first_scale(5.0, -1.0, 1.0, FMAX) == 1.0                 # fits: unscaled
    assert abs(thrust_first_scale(5.0, -4.0, 4.0, FMAX) - 0.5) < 1e-12     # 2 N of room above over 4 N
    assert abs(thrust_first_scale(1.0, -4.0, 4.0, FMAX) - 0.25) < 1e-12    # 1 N of room below over 4 N
    assert thrust_first_scale(0.0, -1.0, 1.0, FMAX) == 0.0                 # no thrust: no differential
