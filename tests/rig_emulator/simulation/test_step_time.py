"""Simulated time in whole microseconds from the integer step counter (message stamps)."""

import numpy as np

from rig_emulator.config.loader import load_config
from rig_emulator.simulation.live import LiveRig
from rig_emulator.simulation.run import step_time_us


def test_step_time_is_exact_where_k_dt_rounds_down():
    ks = np.arange(0, 200_000)
    floats = [int(k * 0.001 * 1000.0) for k in ks]  # what int(t * 1000) of t = k dt gives
    exact = [step_time_us(int(k), 1000.0) // 1000 for k in ks]
    assert exact == list(ks)
    assert sum(a != b for a, b in zip(floats, exact)) > 0  # the float clock is early somewhere
    assert step_time_us(3, 3000.0) == 1000 and step_time_us(7, 1234.5) == round(7e6 / 1234.5)


def test_served_snapshot_carries_the_step_time():
    rig = LiveRig(load_config(scenario="hover"))
    for _ in range(7):
        rig.step(29)
    snap = rig.snapshot()
    assert snap.time_us == 203_000 and snap.stamp_us == 203_000
