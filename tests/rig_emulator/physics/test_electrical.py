"""The bench supply's current (rig_emulator/physics/electrical.py)."""

import numpy as np
import pytest

from rig_emulator.physics.electrical import SEQUENTIAL_SUM_MAX, supply_current, supply_current_sum, torque_constant


def test_torque_constant_of_a_750_kv_motor():
    assert torque_constant(750.0) == pytest.approx(0.012732, rel=1e-4)


def test_hover_current_and_its_scaling():
    f, v = np.full(4, 2.23 * 9.81 / 4), np.full(4, 11.7)
    amps = supply_current(f, v, 15.0, 0.016)
    assert 18.0 < amps < 25.0  # ~6.9 A a motor at 11.7 V of 15 V
    assert supply_current(2 * f, v, 15.0, 0.016) == pytest.approx(2 * amps)
    assert supply_current(f, np.zeros(4), 15.0, 0.016) == 0.0  # motors off: nothing drawn
    rows = supply_current(np.tile(f, (3, 1)), np.tile(v, (3, 1)), 15.0, 0.016)
    assert rows.shape == (3,) and np.allclose(rows, amps)


def test_plain_python_sum_is_bit_identical_to_numpy():
    """The served rig integrates the supply's charge per chunk with supply_current_sum:
    exactly numpy's float(np.sum(supply_current(...))) over short chunks."""
    rng = np.random.default_rng(7)
    for trial in range(20000):
        n = int(rng.integers(1, SEQUENTIAL_SUM_MAX + 1))
        f = rng.normal(5.0, 3.0, size=(n, 4)) * 10.0 ** float(rng.integers(-3, 3))
        v = rng.normal(10.0, 6.0, size=(n, 4))
        if trial % 100 == 0:
            f[0, 1] = np.nan
        km, supply = float(rng.uniform(0.005, 0.05)), float(rng.uniform(5.0, 24.0))
        expected = float(np.sum(supply_current(f, v, supply, km, 750.0)))
        got = supply_current_sum(f.tolist(), v.tolist(), supply, km, 750.0)
        assert got == expected or (np.isnan(got) and np.isnan(expected)), (trial, got, expected)
