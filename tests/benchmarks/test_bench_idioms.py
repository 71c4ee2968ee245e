"""benchmarks/idioms.py: the two slower ways of writing `CascadedPID` fly the same numbers as the example,
bit for bit, so that the share table's rows differ by the Python idiom alone. Flown on the default
`hilms` rig, the helix, 3 s (the position and attitude loops, their integrators and the yaw wrap all
act)."""

import numpy as np
import pytest

from rig_emulator.api import simulate

CASES = ("rig_emulator.controllers.examples.cascaded_pid:CascadedPID", "benchmarks.idioms:CascadedPIDBuiltins",
         "benchmarks.idioms:CascadedPIDNumpy")


@pytest.fixture(scope="module")
def logs():
    return [simulate("helix", strategy="pid", duration=3.0, seed=3, controller=c,
                     overrides={"controller.call": "python"}).log for c in CASES]


def test_the_idioms_fly_the_example_bit_for_bit(logs):
    ref = logs[0]
    assert np.nanmax(np.nanstd(ref, axis=0)) > 0.0
    for c, log in zip(CASES[1:], logs[1:]):
        assert log.shape == ref.shape and np.array_equal(log, ref, equal_nan=True), c
