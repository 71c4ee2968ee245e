"""The rig's compiled waypoint logic is protocol's shared logic, compiled (same numbers)."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from protocol import waypoint_switching as shared
from rig_emulator.guidance import runner
from rig_emulator.guidance import waypoint_switching as compiled

coord = st.floats(-100, 100)


def test_the_step_loop_and_the_ground_tools_use_the_compiled_functions():
    from gcs_tools import fly

    for name in ("leg_duration", "line_setpoint", "waypoint_reached"):
        assert getattr(compiled, name).py_func is getattr(shared, name)
        assert getattr(runner, name) is getattr(compiled, name)
        assert getattr(fly, name) is getattr(compiled, name)


@settings(max_examples=100, deadline=None)
@given(coord, coord, coord, coord, coord, coord, st.floats(0.1, 5.0), st.floats(-0.5, 1.5))
def test_compiled_and_plain_agree(sx, sy, sz, tx, ty, tz, speed, frac):
    T = compiled.leg_duration(sx, sy, sz, tx, ty, tz, speed, 0.5)
    assert math.isclose(T, shared.leg_duration(sx, sy, sz, tx, ty, tz, speed, 0.5), rel_tol=1e-15)
    a, b = (np.zeros(3), np.zeros(3)), (np.zeros(3), np.zeros(3))
    compiled.line_setpoint(frac * T, 0.0, T, sx, sy, sz, tx, ty, tz, *a)
    shared.line_setpoint(frac * T, 0.0, T, sx, sy, sz, tx, ty, tz, *b)
    assert np.allclose(a[0], b[0], rtol=1e-15, atol=1e-12) and np.allclose(a[1], b[1], rtol=1e-15, atol=1e-12)
    assert compiled.waypoint_reached(sx, sy, sz, tx, ty, tz, 1.0) == shared.waypoint_reached(sx, sy, sz, tx, ty, tz, 1.0)
