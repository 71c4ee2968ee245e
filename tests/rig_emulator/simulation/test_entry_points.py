"""The structural key of the step loop's arguments stands for numba's own typing: over every
scenario preset and control strategy, equal keys come with equal numba signatures (so a
cached entry point is never called with arguments of other types), and a rig run through
the cached entry point gives the numbers of one run through numba's dispatcher."""

import numpy as np
import pytest

from rig_emulator.config.loader import available, load_config
from rig_emulator.config.schema import STRATEGIES
from rig_emulator.simulation import entry_points
from rig_emulator.simulation.entry_points import arg_key, signature
from rig_emulator.simulation.loop import run_steps
from rig_emulator.simulation.run import Simulation


def _args(sim):
    """What Simulation._advance passes to the loop (read back from a call)."""
    captured = {}

    def fake(dispatcher, args):
        captured["args"] = args
        return lambda *a: sim.log_row

    real = entry_points.entry_point
    entry_points.entry_point = fake  # what BoundEntry looks the entry point up with
    try:
        sim._loop.forget()
        sim.advance(0)
    finally:
        entry_points.entry_point = real
        sim._loop.forget()
    return captured["args"]


def test_equal_keys_mean_equal_numba_signatures():
    seen = {}
    for scenario in available("scenarios"):
        for strategy in STRATEGIES:
            sim = Simulation(load_config(scenario=scenario, overrides={"control.strategy": strategy,
                                                                       "sim.duration": 0.01}))
            args = _args(sim)
            key = arg_key(args)
            assert key is not None, f"{scenario}/{strategy}: an argument has no structural key"
            sig = signature(run_steps, args)
            assert seen.setdefault(key, sig) == sig, f"{scenario}/{strategy}: one key, two signatures"
    assert len(seen) >= 1


def test_keys_tell_apart_what_numba_tells_apart():
    a = np.zeros((3, 4))
    assert arg_key(a) != arg_key(np.zeros((3, 4), dtype=np.float32))
    assert arg_key(a) != arg_key(np.zeros(12))
    assert arg_key(a) != arg_key(np.asfortranarray(a))
    assert arg_key(a) != arg_key(a[:, ::2])
    ro = a.copy()
    ro.flags.writeable = False
    assert arg_key(a) != arg_key(ro)
    assert arg_key(1) != arg_key(1.0) != arg_key(True)
    assert arg_key(2**64) is None and arg_key([1, 2]) is None and arg_key((1, [2])) is None
    assert arg_key((1, 2.0)) == arg_key((5, 7.5)) != arg_key((1.0, 2))


@pytest.mark.parametrize("scenario", ["hover", "harmonic"])
def test_cached_entry_point_gives_the_dispatcher_numbers(scenario):
    cfg = load_config(scenario=scenario, overrides={"sim.duration": 0.5})
    a = Simulation(cfg)
    a.run()
    b = Simulation(cfg)  # same shape: its entry point comes from the structural cache
    args = _args(b)
    ref_row = run_steps(*args[:1], 500, *args[2:])  # numba's dispatcher, typing every argument
    c = Simulation(cfg)
    c.run()
    assert ref_row == c.log_row
    assert np.array_equal(b.log[:ref_row], c.log[:ref_row], equal_nan=True)
    assert np.array_equal(b.x, c.x)
