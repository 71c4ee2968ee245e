"""ZEMIC L6D load-cell model (paper Sec. 4-1, Fig. 9)."""

import numpy as np

from rig_emulator.sensors.faults import FAULT_DEAD, FAULT_SPIKE, FAULT_STUCK, set_fault
from rig_emulator.sensors.load_cell import GRF_N, draw_load_cells, load_load_cell_config, sample_load_cells


def _run(truth, thrust_grf, speed, n=2000, mode=None, mag=None, seed=1):
    k = truth.kernel
    mode = np.zeros(k.n_cells, dtype=np.int64) if mode is None else mode
    mag = np.zeros(k.n_cells) if mag is None else mag
    raw = np.zeros(k.n_cells)
    rng = np.random.default_rng(seed)
    out = np.zeros((n, k.n_cells))
    for j in range(n):
        sample_load_cells(np.full(k.n_cells, thrust_grf * GRF_N), np.full(k.n_cells, speed), k, mode, mag, rng, raw)
        out[j] = raw
    return out


def test_reading_is_zero_plus_thrust_over_step_and_integer():
    t = draw_load_cells(load_load_cell_config(), np.random.default_rng(4))
    assert np.all(np.abs(t.zero_counts - 350.0) <= 30.0)
    r = _run(t, 500.0, 0.0)
    assert np.all(r == np.round(r))
    assert np.allclose(r.mean(axis=0), t.zero_counts + 500.0 / t.c_grf_per_count, atol=0.2)


def test_noise_grows_with_rotor_speed_and_output_clips():
    cfg = load_load_cell_config()
    t = draw_load_cells(cfg, np.random.default_rng(4))
    quiet = _run(t, 300.0, 0.0).std(axis=0).mean() * 2.44
    hover = _run(t, 300.0, 640.0).std(axis=0).mean() * 2.44
    assert abs(quiet - 2.0) < 0.6            # noise floor 2 grF (plus quantisation)
    assert abs(hover - 22.0) < 2.0           # floor + vibration at hover
    assert np.all(_run(t, 5000.0, 0.0, n=5) == 1023)
    assert np.all(_run(t, -5000.0, 0.0, n=5) == 0)


def test_faults_stuck_dead_spike():
    t = draw_load_cells(load_load_cell_config(), np.random.default_rng(4))
    k = t.kernel
    mode = np.zeros(k.n_cells, dtype=np.int64)
    mag = np.zeros(k.n_cells)
    set_fault(mode, mag, 0, "dead", imu=False)
    set_fault(mode, mag, 2, "spike", 200.0, imu=False)
    r = _run(t, 400.0, 640.0, n=3000, mode=mode, mag=mag)
    assert np.all(r[:, 0] == 0)
    spikes = np.abs(r[:, 2] - np.median(r[:, 2])) > 120
    assert 0.01 < spikes.mean() < 0.03  # spike_probability 0.02
    assert mode[0] == FAULT_DEAD and mode[2] == FAULT_SPIKE
    raw = np.full(k.n_cells, 123.0)
    stuck = np.array([FAULT_STUCK] * k.n_cells, dtype=np.int64)
    sample_load_cells(np.full(k.n_cells, 3.0), np.zeros(k.n_cells), k, stuck, mag, np.random.default_rng(0), raw)
    assert np.all(raw == 123.0)
