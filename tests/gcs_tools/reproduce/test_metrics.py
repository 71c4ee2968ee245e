"""The reproduction's figures of merit on signals whose answer is known in closed form."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from gcs_tools.reproduce.metrics import (divergence_time, hf_rms, improvement_pct, low_part, mean_lag, overshoot_pct,
                                         tilt_chattering_deg,
                                         settling_about_final, settling_time, shock_response, window_mean_abs)

DT = 0.002


@settings(max_examples=40, deadline=None)
@given(amp=st.floats(0.5, 20.0), tau=st.floats(0.05, 1.0), frac=st.floats(0.02, 0.5))
def test_settling_time_of_a_first_order_decay(amp, tau, frac):
    t = np.arange(0.0, 8.0 * tau + 1.0, DT)
    e = amp * np.exp(-t / tau)
    ts = settling_time(t, e, 0.0, t[-1], frac * amp)
    assert abs(ts - tau * math.log(1.0 / frac)) <= DT + 1e-9


@settings(max_examples=40, deadline=None)
@given(zeta=st.floats(0.1, 0.8), wn=st.floats(2.0, 20.0), amp=st.floats(0.5, 10.0), sign=st.sampled_from([-1, 1]))
def test_overshoot_of_an_underdamped_second_order_response(zeta, wn, amp, sign):
    # the error after a unit step: e = -exp(-zeta wn t)(cos wd t + zeta/sqrt(1-zeta^2) sin wd t), peak -1 at t = 0
    wd = wn * math.sqrt(1.0 - zeta**2)
    t = np.arange(0.0, 10.0 / (zeta * wn), 0.002 / wn)
    e = sign * amp * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    expected = 100.0 * math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))
    assert overshoot_pct(e, e[0]) == pytest.approx(expected, rel=1e-3, abs=1e-3)


def test_shock_response_picks_the_disturbed_axis_peak_band_and_settling():
    t = np.arange(0.0, 6.0, DT)
    err = np.zeros((t.size, 3))
    after = t >= 1.0
    err[after, 1] = -4.0 * np.exp(-(t[after] - 1.0) / 0.2)  # a -4 deg kick on theta
    err[:, 0] = 0.01 * np.sin(40 * t)  # noise on phi
    r = shock_response(t, err, 1.0, 5.0, band_frac=0.1, band_min=0.1)
    assert r.axis == 1 and r.peak == pytest.approx(-4.0) and r.t_peak == pytest.approx(1.0)
    assert r.band == pytest.approx(0.4) and r.settling_s == pytest.approx(0.2 * math.log(10), abs=DT)
    assert r.overshoot_pct == 0.0 and r.settled


def test_not_settled_in_the_window_is_inf():
    t = np.arange(0.0, 4.0, DT)
    e = 10.0 * np.exp(-t / 6.0)  # the paper's SMC: lambda = 0.17 1/s
    assert settling_time(t, e, 0.0, 4.0, 1.0) == math.inf
    assert settling_time(t, np.zeros_like(t), 0.0, 4.0, 1.0) == 0.0
    with pytest.raises(ValueError):
        settling_time(t, e, 5.0, 6.0, 1.0)


def test_settling_is_about_the_final_value_not_the_set_point():
    """Fig. 12: a controller without integral action returns to its static offset after a
    shock; it has settled (textbook settling time), though never within a band about zero."""
    t = np.arange(0.0, 4.0, DT)
    offset, tau = 0.4, 0.2
    e = offset + 2.0 * np.exp(-t / tau)  # back to a 0.4 deg offset, band 0.2 deg
    ts, final, band = settling_about_final(t, e, 0.0, t[-1], 0.1, 0.1)
    assert final == pytest.approx(offset, abs=1e-6) and band == pytest.approx(0.2, rel=1e-6)
    assert ts == pytest.approx(tau * math.log(10.0), abs=DT)
    assert settling_time(t, e, 0.0, t[-1], band) == math.inf  # about zero it never settles
    ts, final, band = settling_about_final(t, 2.0 * np.exp(-t / tau), 0.0, t[-1], 0.1, 0.1)
    assert final == pytest.approx(0.0, abs=1e-6) and ts == pytest.approx(tau * math.log(10.0), abs=DT)
    with pytest.raises(ValueError):
        settling_about_final(t, e, 5.0, 6.0, 0.1, final_s=0.5)


def test_a_chattering_response_settles_once_its_chattering_is_removed():
    """The SMC chatters at 6-7 Hz (relay limit cycle through the motor lag) and still settles:
    the response below the chattering cut-off settles, the raw error with +-0.3 deg of
    chattering never enters a 0.2 deg band."""
    t = np.arange(0.0, 4.0, DT)
    response = 2.0 * np.exp(-t / 0.15)
    chatter = 0.3 * np.sin(2 * np.pi * 6.5 * t)
    raw = response + chatter
    assert settling_about_final(t, raw, 0.0, t[-1], 0.1, 0.1)[0] > 3.5  # out of the band until the last cycle
    low = low_part(t, raw, 5.0)
    ts = settling_about_final(t, low, 0.0, t[-1], 0.1, 0.1)[0]
    assert ts == pytest.approx(0.15 * math.log(10.0), abs=0.1)


@settings(max_examples=30, deadline=None)
@given(f=st.floats(0.2, 100.0), a=st.floats(0.1, 5.0), cutoff=st.floats(1.0, 20.0))
def test_low_part_keeps_what_is_well_below_the_cutoff_and_removes_what_is_well_above(f, a, cutoff):
    assume(f <= cutoff / 2.5 or f >= 2.5 * cutoff)
    fs = 500.0
    t = np.arange(5000) / fs
    x = 3.0 + a * np.sin(2 * np.pi * f * t)
    mid = slice(1000, 4000)  # away from the ends
    low = low_part(t, x, cutoff)
    if f < cutoff:
        assert np.max(np.abs(low - x)[mid]) <= 0.03 * a
    else:
        assert np.max(np.abs(low - 3.0)[mid]) <= 0.03 * a
    two = low_part(t, np.column_stack([x, -x]), cutoff)
    assert np.allclose(two[:, 0], low) and np.allclose(two[:, 1], -low)


@settings(max_examples=40, deadline=None)
@given(f=st.floats(0.5, 100.0), a=st.floats(0.1, 5.0), cutoff=st.floats(1.0, 20.0))
def test_hf_rms_of_a_sine_is_its_rms_above_the_cutoff_and_zero_below(f, a, cutoff):
    fs = 500.0
    n = 5000  # 10 s: FFT bins every 0.1 Hz
    f = round(f * 10.0) / 10.0  # on a bin: no spectral leakage
    assume(abs(f - cutoff) >= 0.5)
    t = np.arange(n) / fs
    x = 3.0 + a * np.sin(2 * np.pi * f * t)
    got = hf_rms(t, x, cutoff)
    assert got == pytest.approx(a / math.sqrt(2.0) if f > cutoff else 0.0, rel=1e-6, abs=1e-9)


def test_hf_rms_averages_the_power_of_columns_and_needs_uniform_samples():
    t = np.arange(1000) / 500.0
    x = np.column_stack([np.sin(2 * np.pi * 50 * t), np.zeros_like(t)])
    assert hf_rms(t, x, 5.0) == pytest.approx(math.sqrt(0.25), rel=1e-9)
    with pytest.raises(ValueError, match="uniform"):
        hf_rms(np.r_[t[:500], t[500:] + 0.01], x, 5.0)
    assert math.isnan(hf_rms(t[:3], x[:3], 5.0))


def test_tilt_chattering_reads_the_roll_and_pitch_errors_in_degrees():
    """Figs. 12 and 15's chattering: the roll and pitch errors above the cut-off, in degrees; the
    yaw error, slow motion and a reference the attitude follows do not count."""
    t = np.arange(0.0, 10.0, 0.002)
    slow = np.radians(5.0) * np.sin(2 * math.pi * 0.5 * t)
    euler_des = np.column_stack([slow, -slow, np.zeros_like(t)])
    roll = slow + np.radians(0.3 * math.sqrt(2.0)) * np.sin(2 * math.pi * 7.0 * t)  # 0.3 deg rms at 7 Hz
    pitch = -slow + np.radians(0.4 * math.sqrt(2.0)) * np.sin(2 * math.pi * 11.0 * t)  # 0.4 deg rms at 11 Hz
    yaw = np.radians(2.0) * np.sin(2 * math.pi * 20.0 * t)
    euler = np.column_stack([roll, pitch, yaw])
    got = tilt_chattering_deg(t, euler, euler_des, 5.0)
    assert got == pytest.approx(math.sqrt((0.3 ** 2 + 0.4 ** 2) / 2.0), rel=1e-6)
    assert tilt_chattering_deg(t, euler_des, euler_des, 5.0) == pytest.approx(0.0, abs=1e-12)


def test_divergence_window_and_lag_helpers():
    t = np.arange(0.0, 3.0, 0.01)
    euler = np.zeros((t.size, 3))
    euler[:, 0] = np.radians(30.0 * t)  # crosses 45 deg at 1.5 s
    assert divergence_time(t, euler) == pytest.approx(1.51)
    euler[:, 0] = 0.0
    euler[:, 2] = np.radians(170.0)  # yaw does not count
    assert divergence_time(t, euler) is None
    euler[100, 1] = np.nan
    assert divergence_time(t, euler) == pytest.approx(1.0)
    assert window_mean_abs(t, 2.0 * t, 0.0, 1.0, 2.0) == pytest.approx(3.0)
    assert math.isnan(window_mean_abs(t, t, t, 5.0, 6.0))
    assert mean_lag(t, 0.3 * (t - 0.1), 0.3 * t, (0.0, 3.0)) == pytest.approx(0.03)
    dip = np.where((t > 1.0) & (t < 2.0), 1.0, 0.0)  # a transient between the windows does not count
    assert mean_lag(t, 0.3 * (t - 0.1) - dip, 0.3 * t, (0.0, 1.0), (2.0, 3.0)) == pytest.approx(0.03)
    assert improvement_pct(0.0724, 0.0659) == pytest.approx(8.978, abs=1e-3)  # Table 6, X
    assert improvement_pct(1.0, 2.0) == -100.0 and math.isnan(improvement_pct(0.0, 1.0))
