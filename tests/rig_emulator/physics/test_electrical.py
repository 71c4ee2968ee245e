"""The bench supply's current (rig_emulator/physics/electrical.py)."""

import numpy as np
import pytest

from rig_emulator.physics.electrical import supply_current, torque_constant


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
