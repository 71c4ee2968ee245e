"""Eq. 33-35: Eq. 35 inverts Eq. 34, the direction is a unit vector, the singularity is guarded."""

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.control.thrust_direction import TILT_CLAMPED, collective_thrust, desired_tilt, thrust_direction

MAX_TILT = math.radians(35.0)


@settings(max_examples=300, deadline=None)
@given(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6), st.floats(-math.pi, math.pi))
def test_eq35_inverts_eq34(phi, theta, psi):
    ux, uy, uz = thrust_direction(phi, theta, psi)
    assert math.isclose(ux * ux + uy * uy + uz * uz, 1.0, rel_tol=1e-12)
    phi_d, theta_d, flags = desired_tilt(ux, uy, psi, math.radians(80.0))
    assert flags == 0
    assert math.isclose(phi_d, phi, abs_tol=1e-9) and math.isclose(theta_d, theta, abs_tol=1e-9)


@settings(max_examples=300, deadline=None)
@given(st.floats(-5, 5), st.floats(-5, 5), st.floats(-math.pi, math.pi))
def test_clamp_keeps_tilt_within_the_limit(ux, uy, psi):
    phi_d, theta_d, flags = desired_tilt(ux, uy, psi, MAX_TILT)
    tx, ty, tz = thrust_direction(phi_d, theta_d, psi)
    assert tz >= math.cos(MAX_TILT) - 1e-12
    if math.hypot(ux, uy) > math.sin(MAX_TILT):
        assert flags & TILT_CLAMPED


def test_collective_thrust_is_eq33_third_row():
    phi, theta = 0.2, -0.1
    assert math.isclose(collective_thrust(21.9, phi, theta, MAX_TILT) * math.cos(phi) * math.cos(theta), 21.9)
    assert collective_thrust(-5.0, 0.0, 0.0, MAX_TILT) == 0.0
