"""The load cells as if no guard had held a reading (gcs_tools/identify/motor_chain.py, ``repaired_cells``).

A synthetic log: commands that swing the motors between stop and full supply, so that the thrust jumps
by about the jump guard's threshold between two load-cell samples; readings with the datasheet's noise,
passed through the firmware's own guard and IIR (estimation/load_cell_filter.py). The
repaired series must follow the readings the guard would have let through, and the noise it expects
must leave out the replaced readings.
"""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.signal import lfilter

from gcs_tools.identify.motor_chain import LC_STEP_N, MotorChainModel, cell_noise_sd, held_samples, repaired_cells
from gcs_tools.identify.rig_constants import rig_constants
from rig_emulator.config.loader import load_config
from rig_emulator.estimation.load_cell_filter import (FILTER_IIR, LcFilterParams, load_cell_filter_state,
                                                      load_cell_filter_step)

P = np.array([1.02, 0.98, 1.0, 1.01, -0.3, 1.7, 0.013])  # gains, bias (N), curve exponent, delay (s)


def _guard_and_iir(raw, rc):
    """The firmware's own guards and IIR (estimation/load_cell_filter.py), sample by sample, on raw
    readings (N, counted at 1 N a count): the filtered thrusts and which readings a guard rejected."""
    p = LcFilterParams(mode=FILTER_IIR, zero_counts=np.zeros(4), newton_per_count=np.ones(4),
                       jump_threshold_N=rc.lc_jump_N, max_thrust_N=rc.lc_max_N, min_thrust_N=-1e9,
                       reaccept_after=rc.lc_reaccept, iir_alpha=rc.lc_alpha, kalman_gain=np.zeros(2),
                       dt_s=rc.dt * rc.lc_decim)
    state = load_cell_filter_state(4)
    y = np.empty_like(raw)
    held = np.zeros(raw.shape, dtype=bool)
    out = np.empty(4)
    for j in range(raw.shape[0]):
        rejected = load_cell_filter_step(raw[j], p, state, out)
        y[j] = out
        held[j] = [(rejected >> i) & 1 for i in range(4)]
    return y, held


@pytest.fixture(scope="module")
def swinging_log():
    rc = rig_constants(load_config(airframe="hilms", scenario="sysid"))
    t = np.arange(0.0, 12.0, 0.002)  # rows at 500 Hz: every 5 ms load-cell sample shows
    v = np.where((t // 0.4) % 2 == 0, 4.0, rc.v_max)[:, None] * np.ones(4)
    v[:, 1] = np.where((t // 0.3) % 2 == 0, rc.v_max, 3.0)
    model = MotorChainModel(t, v, rc)
    f = model.thrust(P, model.voltages(P[6], model.k_lc))
    rng = np.random.default_rng(7)
    raw = f + cell_noise_sd(rc, f) * rng.standard_normal(f.shape)
    y, held = _guard_and_iir(raw, rc)
    a = rc.lc_alpha
    unguarded = lfilter([a], [1.0, -(1.0 - a)], raw, axis=0, zi=(1.0 - a) * raw[:1])[0]
    rows = model.row_in_lc
    log = SimpleNamespace(t=t, v_cmd=v, thrust=y[rows], t_cmd=t, t_cells=t)
    return rc, model, log, held, unguarded[rows]


def test_the_guard_holds_readings_in_the_synthetic_log(swinging_log):
    rc, model, log, held, _ = swinging_log
    assert held.any(axis=1).mean() > 0.02  # the case the repair is for
    found = held_samples(log, model, P)
    # what held_samples sees is what the guard held, where holding changed the reading
    assert (found & held).sum() >= 0.8 * found.sum()


def test_repaired_cells_follow_the_readings_the_guard_would_have_passed(swinging_log):
    rc, model, log, held, unguarded = swinging_log
    rep = repaired_cells(log, model, P)
    assert rep is not None and rep.rows.all() and rep.held_share > 0.0
    guarded_err = np.abs(log.thrust - unguarded)
    repaired_err = np.abs(rep.thrust - unguarded)
    # a held sample puts the chain's thrust in place of a noisy reading: what is left is those samples' noise
    # through the filter, not the stale value's memory
    assert repaired_err.max() < 0.05 * guarded_err.max()
    assert np.sqrt(np.mean(repaired_err ** 2)) < 0.03 * np.sqrt(np.mean(guarded_err ** 2))


def test_repaired_noise_leaves_out_the_replaced_readings(swinging_log):
    rc, model, log, held, _ = swinging_log
    rep = repaired_cells(log, model, P)
    f = model.thrust(P, model.voltages(P[6], model.k_lc))
    a = rc.lc_alpha
    v_raw = cell_noise_sd(rc, f) ** 2 + LC_STEP_N ** 2 / 12.0
    b = (1.0 - a) ** 2
    every = lfilter([a * a], [1.0, -b], v_raw, axis=0, zi=b * a / (2.0 - a) * v_raw[:1])[0][model.row_in_lc]
    assert np.all(rep.noise_var <= every * (1.0 + 1e-9))
    # after a replaced reading the expected noise is below what every reading's noise would give
    assert np.any(rep.noise_var < 0.9 * every)


def test_no_repair_without_every_sample():
    rc = rig_constants(load_config(airframe="hilms", scenario="sysid"))
    t = np.arange(0.0, 4.0, 0.02)  # 50 Hz rows: the filter cannot be inverted sample by sample
    v = np.full((t.size, 4), 11.0)
    log = SimpleNamespace(t=t, v_cmd=v, thrust=np.full((t.size, 4), 5.0), t_cmd=t, t_cells=t)
    assert repaired_cells(log, MotorChainModel(t, v, rc), P) is None
