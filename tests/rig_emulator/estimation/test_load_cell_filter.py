"""Load-cell thrust chain: Sec. 3-2 guards, the paper's IIR and the steady-state Kalman."""

import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from rig_emulator.estimation.estimation_config import load_estimation_config
from rig_emulator.estimation.load_cell_calibration import LoadCellCalibration
from rig_emulator.estimation.load_cell_filter import (
    design_thrust_kalman_gain, load_cell_filter_params, load_cell_filter_state, load_cell_filter_step,
    thrust_kalman_model)
from rig_emulator.sensors.load_cell import GRF_N

CAL = LoadCellCalibration(np.full(4, 350.0), np.full(4, 2.44))
DT = 5e-3


def _params(**over):
    return load_cell_filter_params(load_estimation_config({"load_cell_filter": over}), CAL, DT)


def _counts(grf):
    return 350.0 + np.asarray(grf) / 2.44


def test_steady_state_gain_matches_filterpy_iterated():
    F, H, Q, R = thrust_kalman_model(DT, 22 * GRF_N, 50 * GRF_N)
    kf = KalmanFilter(dim_x=2, dim_z=1)
    kf.F, kf.H, kf.Q, kf.R = F, H, Q, R
    kf.P *= 10.0
    for _ in range(3000):
        kf.predict()
        kf.update(np.array([0.0]))
    assert np.allclose(kf.K[:, 0], design_thrust_kalman_gain(DT, 22 * GRF_N, 50 * GRF_N), rtol=1e-6)


def test_guards_hold_previous_value_on_jumps_and_above_850_grf():
    p = _params(mode="none", reaccept_after=3)
    s = load_cell_filter_state(4)
    out = np.zeros(4)
    load_cell_filter_step(_counts([400, 400, 400, 400]), p, s, out)
    rej = load_cell_filter_step(_counts([450, 900, 400 + 150, 0]), p, s, out)
    assert rej == 0b1110
    assert np.allclose(out / GRF_N, [450, 400, 400, 400], atol=1e-9)
    for _ in range(3):  # a genuine step is accepted again after 3 rejections; > 850 never
        rej = load_cell_filter_step(_counts([450, 900, 550, 550]), p, s, out)
    assert np.allclose(out / GRF_N, [450, 400, 550, 550], atol=1e-9)
    p0 = _params(mode="none", reaccept_after=0)  # paper-faithful: never
    s0 = load_cell_filter_state(4)
    load_cell_filter_step(_counts([400] * 4), p0, s0, out)
    for _ in range(100):
        load_cell_filter_step(_counts([550] * 4), p0, s0, out)
    assert np.allclose(out / GRF_N, 400.0)


def test_floor_guard_rejects_a_dead_cell_for_good():
    """A dead cell (0 counts, about -850 grF) is discarded like a reading above the
    ceiling - never re-accepted - so its thrust stays at the last accepted reading."""
    p = _params(mode="iir", reaccept_after=3)
    s = load_cell_filter_state(4)
    out = np.zeros(4)
    load_cell_filter_step(_counts([550] * 4), p, s, out)
    for _ in range(200):
        rej = load_cell_filter_step(np.array([*_counts([550] * 3), 0.0]), p, s, out)
        assert rej == 0b1000
    assert out[3] / GRF_N == pytest.approx(550.0)
    off = _params(mode="iir", reaccept_after=3, min_thrust_grf=-1e5)  # without the floor: re-accepted
    s = load_cell_filter_state(4)
    load_cell_filter_step(_counts([550] * 4), off, s, out)
    for _ in range(200):
        load_cell_filter_step(np.array([*_counts([550] * 3), 0.0]), off, s, out)
    assert out[3] / GRF_N < -800.0


def _run(mode, thrust_grf, seed=0, noise_grf=22.0):
    p = _params(mode=mode)
    s = load_cell_filter_state(4)
    out = np.zeros(4)
    rng = np.random.default_rng(seed)
    y = np.zeros((len(thrust_grf), 4))
    for k, f in enumerate(thrust_grf):
        counts = np.floor(_counts(f + rng.normal(0, noise_grf, 4)) + 0.5)  # hover vibration noise
        load_cell_filter_step(counts, p, s, out)
        y[k] = out / GRF_N
    return y


def test_kalman_lags_less_than_the_iir_at_no_more_noise():
    n = 4000
    t = np.arange(n) * DT
    steady = np.full(n, 550.0)
    noise_iir = _run("iir", steady)[400:].std()
    noise_kf = _run("kalman", steady)[400:].std()
    harmonic = 550.0 + 60.0 * np.sin(2 * math.pi * 0.5 * t)  # Fig. 9b-like harmonic thrust
    lags = {}
    for mode in ("iir", "kalman"):
        y = _run(mode, harmonic, seed=1)[400:, 0] - 550.0
        x = harmonic[400:] - 550.0
        shifts = np.arange(0, 100)
        corr = [np.dot(x[: len(x) - d], y[d:]) for d in shifts]
        lags[mode] = shifts[int(np.argmax(corr))] * DT
    ramp = 300.0 + 25.0 * t  # 25 grF/s thrust ramp, within the 850 grF ceiling; lag of the noise-free ramp
    ramp_lag = {m: np.mean(ramp[400:, None] - _run(m, ramp, noise_grf=0.0)[400:]) / 25.0 for m in ("iir", "kalman")}
    raw_noise = _run("none", steady)[400:].std()
    print(f"\noutput noise [grF]: raw {raw_noise:.2f}, iir {noise_iir:.2f}, kalman {noise_kf:.2f}; "
          f"delay on a 0.5 Hz harmonic [ms]: iir {lags['iir'] * 1e3:.0f}, kalman {lags['kalman'] * 1e3:.0f}; "
          f"ramp lag [ms]: iir {ramp_lag['iir'] * 1e3:.1f}, kalman {ramp_lag['kalman'] * 1e3:.1f}")
    assert noise_kf <= noise_iir
    assert lags["kalman"] < lags["iir"]
    assert abs(ramp_lag["kalman"]) < 0.25 * ramp_lag["iir"]
    assert noise_iir < 0.5 * raw_noise
