"""Tests of the virtual barometer (ISA troposphere)."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from rig_emulator.sensors.barometer import ISA_P0_PA, isa_altitude, isa_pressure_temperature


def test_standard_values():
    """ICAO standard atmosphere table: 101325 Pa / 15 C at 0 m, 89874.6 Pa / 8.5 C at 1000 m,
    54019.9 Pa / -17.5 C at 5000 m."""
    p, t = isa_pressure_temperature(0.0)
    assert p == ISA_P0_PA and t == 288.15
    p, t = isa_pressure_temperature(1000.0)
    assert abs(p - 89874.6) < 1.0 and abs(t - 281.65) < 1e-9
    p, t = isa_pressure_temperature(5000.0)
    assert abs(p - 54019.9) < 2.0 and abs(t - 255.65) < 1e-9


@given(st.floats(-500.0, 11000.0))
def test_altitude_inverts_pressure(h):
    p, _ = isa_pressure_temperature(h)
    assert abs(isa_altitude(p) - h) < 1e-6


def test_pressure_falls_about_12_pa_per_metre_near_the_ground():
    p0, _ = isa_pressure_temperature(1200.0)
    p1, _ = isa_pressure_temperature(1201.0)
    assert 10.0 < p0 - p1 < 12.5


def test_saturates_instead_of_failing():
    assert isa_pressure_temperature(50_000.0) == isa_pressure_temperature(11_000.0)
    assert isa_pressure_temperature(-9_000.0) == isa_pressure_temperature(-500.0)
    p, t = isa_pressure_temperature(math.nan)
    assert math.isfinite(p) and math.isfinite(t)
