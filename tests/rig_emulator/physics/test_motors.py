"""Eq. 40 motor map, supply and thrust limits, Eq. 38 rotor speed."""

import math

from hypothesis import given
from hypothesis import strategies as st

from rig_emulator.physics.motors import GRAM_FORCE_N, rotor_speed, thrust_from_voltage, voltage_for_thrust

K_V = 47.62 * GRAM_FORCE_N
CEIL = 850 * GRAM_FORCE_N


def test_eq40_at_a_known_voltage():
    assert math.isclose(thrust_from_voltage(10.0, K_V, CEIL) / GRAM_FORCE_N, 476.2, rel_tol=1e-12)


def test_ceiling_and_floor():
    assert thrust_from_voltage(100.0, K_V, CEIL) == CEIL
    assert thrust_from_voltage(-1.0, K_V, CEIL) == 0.0


@given(st.floats(0.0, 7.0))
def test_voltage_inverts_eq40_inside_the_supply(f):
    v = voltage_for_thrust(f, K_V, 15.0)
    assert 0.0 <= v <= 15.0
    if f <= K_V * 15.0:
        assert math.isclose(thrust_from_voltage(v, K_V, CEIL), f, rel_tol=1e-12, abs_tol=1e-12)
    else:
        assert v == 15.0


@given(st.floats(1e-3, 10.0))
def test_rotor_speed_satisfies_eq38(f):
    w = rotor_speed(f, 1.3e-5)
    assert math.isclose(1.3e-5 * w * w, f, rel_tol=1e-12)
