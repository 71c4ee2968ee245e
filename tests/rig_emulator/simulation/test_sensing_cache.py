"""build_sensing: a rig's sensing is built once per sensing configuration and copied for each
run. The copy runs bit-identically to a Sensing built from scratch, the cache key holds every
config key a build reads, and what differs (seed, sensor parameters, a rewritten calibration
file) builds anew."""

import os

import numpy as np
import pytest

from rig_emulator.config.loader import RigConfig, load_config
from rig_emulator.config.schema import STRATEGIES
from rig_emulator.estimation.calibration_file import save_calibration
from rig_emulator.simulation import sensing as sensing_mod
from rig_emulator.simulation.run import Simulation
from rig_emulator.simulation.sensing import SENSING_KEYS, Sensing, build_sensing


class _Recording(RigConfig):
    def __init__(self, *a):
        super().__init__(*a)
        self.read = set()

    def __getitem__(self, key):
        self.read.add(key)
        return super().__getitem__(key)

    def get(self, key, default=None):
        self.read.add(key)
        return super().get(key, default)


@pytest.mark.parametrize("calibration", ["levenberg-marquardt", "none"])
def test_a_build_reads_only_the_keyed_config(calibration):
    for strategy in STRATEGIES:
        cfg = _Recording(load_config(scenario="hover", overrides={"control.strategy": strategy,
                                                                  "sensors.calibration": calibration}))
        Sensing(cfg, 1e-3, np.random.SeedSequence(cfg["sim.seed"]))
        cfg.read.discard("sim.seed")
        outside = sorted(k for k in cfg.read if not k.startswith(SENSING_KEYS))
        assert not outside, f"Sensing reads {outside}: add them to SENSING_KEYS"


def _run(cfg):
    sim = Simulation(cfg)
    r = sim.run()
    return r.log, sim.x.copy()


def test_a_copy_runs_bit_identically_to_a_fresh_build():
    cfg = load_config(scenario="harmonic", overrides={"sim.duration": 0.6, "sim.seed": 11})
    sensing_mod._BUILT.clear()
    fresh = _run(cfg)  # built from scratch (and kept)
    assert len(sensing_mod._BUILT) == 1
    copied_a = _run(load_config(scenario="harmonic", overrides={"sim.duration": 0.6, "sim.seed": 11}))
    copied_b = _run(cfg)  # a second copy: the kept Sensing was not changed by the first run
    assert len(sensing_mod._BUILT) == 1
    for got in (copied_a, copied_b):
        assert np.array_equal(fresh[0], got[0], equal_nan=True) and np.array_equal(fresh[1], got[1])
    other_gain = _run(load_config(scenario="harmonic", overrides={"sim.duration": 0.6, "sim.seed": 11,
                                                                   "guidance.omega": 1.3}))
    assert len(sensing_mod._BUILT) == 1  # a guidance change shares the sensing
    assert not np.array_equal(fresh[0], other_gain[0], equal_nan=True)


def test_what_changes_the_sensing_builds_anew(tmp_path):
    sensing_mod._BUILT.clear()
    base = {"sim.duration": 0.1, "sim.seed": 4}
    a = build_sensing(load_config(scenario="hover", overrides=base), 1e-3)
    b = build_sensing(load_config(scenario="hover", overrides={**base, "sim.seed": 5}), 1e-3)
    assert not np.array_equal(a.imu_truth.kernel.err_matrix, b.imu_truth.kernel.err_matrix)
    build_sensing(load_config(scenario="hover", overrides={**base, "estimation.tau_roll_pitch": 0.9}), 1e-3)
    assert len(sensing_mod._BUILT) == 3
    cal_file = tmp_path / "cal.json"
    save_calibration(cal_file, a.imu_calibration)
    with_file = {**base, "sensors.calibration_file": str(cal_file)}
    first = build_sensing(load_config(scenario="hover", overrides=with_file), 1e-3)
    cal = a.imu_calibration
    cal.gain = cal.gain * 1.01
    save_calibration(cal_file, cal)  # rewritten (by rename): the next build reads it
    os.utime(cal_file, ns=(os.stat(cal_file).st_atime_ns, os.stat(cal_file).st_mtime_ns + 1))
    second = build_sensing(load_config(scenario="hover", overrides=with_file), 1e-3)
    assert np.allclose(second.imu_calibration.gain, first.imu_calibration.gain * 1.01)
