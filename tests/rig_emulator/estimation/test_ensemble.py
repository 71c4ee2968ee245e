"""Ensemble of the IMU modules (paper Sec. 4-1 average; robust options)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.estimation.ensemble import (
    ENSEMBLE_MEAN, ENSEMBLE_MEDIAN, ENSEMBLE_ROBUST_MEAN, ensemble_params, ensemble_state, ensemble_step,
    ensemble_vectors)
from rig_emulator.estimation.estimation_config import load_estimation_config
from rig_emulator.sensors.sensor_step import SAMPLED_INERTIAL, SAMPLED_MAG

vec = st.lists(st.floats(-100, 100), min_size=45, max_size=45)


@settings(max_examples=60, deadline=None)
@given(vec)
def test_mean_and_median_match_numpy(values):
    v = np.array(values).reshape(5, 3, 3)
    out = np.zeros(3)
    scratch = np.zeros(5)
    for s in range(3):
        assert ensemble_vectors(v, s, ENSEMBLE_MEAN, 1.0, scratch, out) == 0
        assert np.allclose(out, v[:, s].mean(axis=0))
        ensemble_vectors(v, s, ENSEMBLE_MEDIAN, 1.0, scratch, out)
        assert np.array_equal(out, np.median(v[:, s], axis=0))


def test_robust_mean_rejects_the_outlier_and_flags_it():
    rng = np.random.default_rng(0)
    v = np.zeros((5, 3, 3))
    v[:, 1] = [0.0, 0.0, -9.81] + rng.normal(0, 0.01, (5, 3))
    v[3, 1] = [0.0, 0.0, 0.0]  # dead accelerometer
    out = np.zeros(3)
    rej = ensemble_vectors(v, 1, ENSEMBLE_ROBUST_MEAN, 0.8, np.zeros(5), out)
    assert rej == 1 << 3
    assert np.allclose(out, np.delete(v[:, 1], 3, axis=0).mean(axis=0))
    v[:, 1] = rng.normal(0, 5.0, (5, 3))  # all far apart: falls back to the median
    rej = ensemble_vectors(v, 1, ENSEMBLE_ROBUST_MEAN, 0.01, np.zeros(5), out)
    assert rej == 0b11111 and np.array_equal(out, np.median(v[:, 1], axis=0))


def test_step_health_mask_and_rates():
    p = ensemble_params(load_estimation_config())
    s = ensemble_state(5)
    v = np.zeros((5, 3, 3))
    v[:, 2] = [20e-6, 0.0, -30e-6]
    v[1, 2] = [0.0, 0.0, 0.0]  # magnetometer of module 1 dead
    out = np.zeros((3, 3))
    assert ensemble_step(v, SAMPLED_INERTIAL | SAMPLED_MAG, p, s, out) == 1 << 1
    v[1, 2] = v[0, 2]
    assert ensemble_step(v, SAMPLED_INERTIAL, p, s, out) == 1 << 1  # mag not resampled: flag kept
    assert ensemble_step(v, SAMPLED_INERTIAL | SAMPLED_MAG, p, s, out) == 0


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6), min_size=5, max_size=5))
def test_median_of_five_network_equals_numpy(values):
    from rig_emulator.estimation.ensemble import _median5

    assert _median5(*values) == float(np.median(values))
