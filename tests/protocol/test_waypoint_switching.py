"""Sec. 4-4 shared waypoint logic: the virtual line, its time budget, the switching radius."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from protocol.waypoint_switching import leg_duration, line_setpoint, waypoint_reached

coord = st.floats(-100, 100)


@settings(max_examples=200, deadline=None)
@given(coord, coord, coord, coord, coord, coord, st.floats(0.1, 5.0), st.floats(0.0, 1.0))
def test_line_runs_from_start_to_target_in_its_budget(sx, sy, sz, tx, ty, tz, speed, frac):
    T = leg_duration(sx, sy, sz, tx, ty, tz, speed, 0.5)
    d = math.dist((sx, sy, sz), (tx, ty, tz))
    assert math.isclose(T, max(d / speed, 0.5), rel_tol=1e-12)
    pos, vel = np.zeros(3), np.zeros(3)
    line_setpoint(10.0 + frac * T, 10.0, T, sx, sy, sz, tx, ty, tz, pos, vel)
    assert np.allclose(pos, [sx + (tx - sx) * frac, sy + (ty - sy) * frac, sz + (tz - sz) * frac], atol=1e-9)
    line_setpoint(10.0 + T + 1.0, 10.0, T, sx, sy, sz, tx, ty, tz, pos, vel)
    assert np.allclose(pos, [tx, ty, tz]) and np.all(vel == 0.0)


def test_velocity_on_the_line():
    pos, vel = np.zeros(3), np.zeros(3)
    line_setpoint(1.0, 0.0, 10.0, 0, 0, 0, 5, 0, 0, pos, vel)
    assert np.allclose(vel, [0.5, 0, 0])


def test_switching_radius_is_strict():
    assert waypoint_reached(0.079, 0.0, 0.0, 0.0, 0.0, 0.0, 0.08)
    assert not waypoint_reached(0.08, 0.0, 0.0, 0.0, 0.0, 0.0, 0.08)
    assert not waypoint_reached(0.05, 0.05, 0.05, 0.0, 0.0, 0.0, 0.08)
