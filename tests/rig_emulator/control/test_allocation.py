"""A6 inverted: exact round trip inside the limits, attitude authority kept first when saturating."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.control.allocation import (
    SATURATED_COLLECTIVE,
    SATURATED_ROLL_PITCH,
    SATURATED_YAW,
    allocate,
    euler_torque_to_body,
)

L, C, FMAX = 0.28, 0.016, 7.0


def _a6(f):
    return f.sum(), L * (f[3] - f[1]), L * (f[0] - f[2]), C * (f[0] - f[1] + f[2] - f[3])


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(0.0, FMAX), min_size=4, max_size=4))
def test_round_trip_inside_limits(forces):
    f = np.array(forces)
    out = np.zeros(4)
    flags = allocate(*_a6(f), L, C, FMAX, out)
    assert flags == 0
    assert np.allclose(out, f, atol=1e-9)


@settings(max_examples=300, deadline=None)
@given(st.floats(-50, 80), st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 1))
def test_outputs_always_within_limits(u1, u2, u3, u4):
    out = np.zeros(4)
    allocate(u1, u2, u3, u4, L, C, FMAX, out)
    assert np.all(out >= 0.0) and np.all(out <= FMAX)


@settings(max_examples=200, deadline=None)
@given(st.floats(0, 40), st.floats(-0.9, 0.9), st.floats(-0.9, 0.9), st.floats(-0.5, 0.5))
def test_roll_pitch_kept_when_only_collective_or_yaw_saturate(u1, u2, u3, u4):
    out = np.zeros(4)
    flags = allocate(u1, u2, u3, u4, L, C, FMAX, out)
    if not flags & SATURATED_ROLL_PITCH:
        _, a2, a3, _ = _a6(out)
        assert abs(a2 - u2) < 1e-9 and abs(a3 - u3) < 1e-9


def test_collective_gives_way_to_roll():
    out = np.zeros(4)
    flags = allocate(4 * FMAX, 0.5, 0.0, 0.0, L, C, FMAX, out)
    assert flags & SATURATED_COLLECTIVE and not flags & SATURATED_ROLL_PITCH
    assert abs(_a6(out)[1] - 0.5) < 1e-12


def test_yaw_is_last():
    out = np.zeros(4)
    flags = allocate(4 * 5.5, 0.0, 0.0, 1.0, L, C, FMAX, out)
    assert flags & SATURATED_YAW
    u1, u2, u3, u4 = _a6(out)
    assert abs(u1 - 22.0) < 1e-9 and abs(u2) < 1e-12 and abs(u3) < 1e-12 and 0 < u4 < 1.0


def test_euler_to_body_flip():
    assert euler_torque_to_body(1.0, 2.0, 3.0) == (1.0, -2.0, -3.0)
