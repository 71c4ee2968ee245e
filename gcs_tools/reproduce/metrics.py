"""Figures of merit the paper reads off its plots (Figs. 12, 15, 17, 18), made computable.

The paper gives no formulas for these; each function documents the one used here:

* :func:`shock_response` - after a shock (Fig. 12): the peak deviation, the settling time
  into a band about the desired value, the overshoot past it;
* :func:`settling_about_final` - the textbook settling time (into a band about the response's
  final value) of a response, and :func:`low_part`, a signal low-passed at the cut-off
  :func:`hf_rms` uses (Fig. 12: the response without its chattering);
* :func:`hf_rms` - chattering (Figs. 12, 15) and high-frequency thrust fluctuation
  (Fig. 18): RMS of the part of a signal above a cut-off frequency;
* :func:`divergence_time` - when a run leaves the attitude envelope (Fig. 15 with SMC);
* :func:`window_mean_abs`, :func:`mean_lag` - altitude error and lag (Figs. 16-17);
* :func:`improvement_pct` - relative improvement as the paper states it (Table 4, Table 6).

All take NumPy arrays with time in seconds; none of them look at wall-clock time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: |phi| or |theta| beyond this (degrees) counts as diverged: the attitude controllers
#: linearise about hover and the paper's rig would be off its joint's useful range.
DIVERGENCE_DEG = 45.0


@dataclass(frozen=True)
class ShockResponse:
    """One shock: the deviation it caused and how the controller recovered."""

    t_shock: float
    t_end: float  # end of the window examined (next shock or end of run)
    axis: int  # 0 phi, 1 theta, 2 psi
    peak: float  # signed peak deviation from the desired value
    t_peak: float
    band: float  # settling band half-width
    settling_s: float  # time from the shock until the deviation stays in the band; inf: not settled in the window
    overshoot_pct: float  # largest excursion past the desired value, % of |peak|

    @property
    def settled(self) -> bool:
        return math.isfinite(self.settling_s)


def settling_time(t, e, t0: float, t1: float, band: float) -> float:
    """Time after ``t0`` from which ``|e|`` stays within ``band`` up to ``t1``.

    0 when it never leaves the band; ``inf`` when it is still outside at the last sample of
    the window (not settled). ``t`` must be increasing.
    """
    if not band > 0:
        raise ValueError(f"band {band!r}: must be > 0")
    t = np.asarray(t, dtype=float)
    e = np.asarray(e, dtype=float)
    sel = np.flatnonzero((t >= t0) & (t <= t1))
    if sel.size == 0:
        raise ValueError(f"no samples in [{t0:g}, {t1:g}]")
    outside = np.flatnonzero(~(np.abs(e[sel]) <= band))  # NaN counts as outside
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    if last == sel.size - 1:
        return math.inf
    return float(t[sel[last + 1]] - t0)


def overshoot_pct(e_after_peak, peak: float) -> float:
    """Largest excursion of ``e`` to the side opposite ``peak``, as a percentage of ``|peak|``."""
    if peak == 0 or not math.isfinite(peak):
        return 0.0
    e = np.asarray(e_after_peak, dtype=float)
    if e.size == 0:
        return 0.0
    past = np.max(-math.copysign(1.0, peak) * e)
    return float(max(past, 0.0) / abs(peak) * 100.0)


def shock_response(t, err, t0: float, t1: float, band_frac: float = 0.1, band_min: float = 0.0,
                   axes=(0, 1)) -> ShockResponse:
    """The response to a shock at ``t0`` examined until ``t1``.

    ``err`` (N, k) is actual minus desired. The axis is the one of ``axes`` whose deviation
    changes most in the window; the peak is its largest ``|err|`` there; the settling band
    is ``max(band_frac |peak|, band_min)``; the overshoot is measured after the peak.
    """
    t = np.asarray(t, dtype=float)
    err = np.asarray(err, dtype=float)
    sel = np.flatnonzero((t >= t0) & (t <= t1))
    if sel.size < 2:
        raise ValueError(f"shock window [{t0:g}, {t1:g}] holds fewer than two samples")
    w = err[sel]
    swing = [np.nanmax(np.abs(w[:, a] - w[0, a])) for a in axes]
    axis = axes[int(np.argmax(swing))]
    e = w[:, axis]
    k = int(np.nanargmax(np.abs(e)))
    peak = float(e[k])
    band = max(band_frac * abs(peak), band_min)
    return ShockResponse(
        t_shock=float(t0), t_end=float(t1), axis=axis, peak=peak, t_peak=float(t[sel[k]]), band=band,
        settling_s=settling_time(t, err[:, axis], t0, t1, band), overshoot_pct=overshoot_pct(e[k:], peak))


def low_part(t, x, cutoff_hz: float):
    """``x`` low-passed at ``cutoff_hz``: the slow response without the content :func:`hf_rms` measures.

    A second-order Butterworth run forwards and backwards (``scipy.signal.filtfilt``): zero
    phase, so it neither delays nor advances a response, and without the long ringing of an
    FFT brick-wall around a shock. Gain at the cut-off 0.5, at 1.3x it (the 6.5 Hz of a 5 Hz
    cut-off) 0.26, at 2x 0.06. ``x`` (N,) or (N, k) sampled uniformly at ``t``.
    """
    from scipy.signal import butter, filtfilt

    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = t.size
    if n < 16 or x.shape[0] != n:
        raise ValueError("low_part needs at least 16 samples, one per time")
    dt = (t[-1] - t[0]) / (n - 1)
    if not dt > 0 or not np.allclose(np.diff(t), dt, rtol=1e-6, atol=1e-9):
        raise ValueError("low_part needs uniformly sampled data")
    b, a = butter(2, cutoff_hz, fs=1.0 / dt)
    return filtfilt(b, a, x, axis=0)


def settling_about_final(t, e, t0: float, t1: float, band_frac: float, band_min: float = 0.0,
                         final_s: float = 1.0) -> tuple[float, float, float]:
    """The textbook settling time of the response ``e`` after ``t0``, examined until ``t1``.

    Settling time is the time after which the response stays within a band about its *final*
    value (Ogata, Modern Control Engineering, Sec. 5-3), not about the set-point: a controller
    without integral action that returns to its static offset has settled. The final value is
    the mean of ``e`` over the last ``final_s`` seconds of the window; the band is
    ``max(band_frac |peak - final|, band_min)``, the peak the largest deviation from it.
    Returns ``(settling_s, final, band)``; ``settling_s`` is ``inf`` when ``e`` is still
    outside the band at the end of the window.
    """
    t = np.asarray(t, dtype=float)
    e = np.asarray(e, dtype=float)
    fin = (t >= t1 - final_s) & (t <= t1)
    if not fin.any():
        raise ValueError(f"no samples in the final {final_s:g} s of [{t0:g}, {t1:g}]")
    final = float(np.mean(e[fin]))
    sel = (t >= t0) & (t <= t1)
    peak = float(np.nanmax(np.abs(e[sel] - final)))
    band = max(band_frac * peak, band_min)
    return settling_time(t, e - final, t0, t1, band), final, band


def hf_rms(t, x, cutoff_hz: float) -> float:
    """RMS of the content of ``x`` above ``cutoff_hz`` (mean over columns of the power).

    ``x`` (N,) or (N, k) sampled uniformly at ``t``; the mean is removed and the one-sided
    FFT power above the cut-off summed (Parseval), so a sine of amplitude A above the
    cut-off gives A / sqrt(2) and one below it about 0. NaN when fewer than 4 samples.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    n = t.size
    if n < 4 or x.shape[0] != n:
        return math.nan
    dt = (t[-1] - t[0]) / (n - 1)
    if not dt > 0:
        raise ValueError("time must increase")
    if not np.allclose(np.diff(t), dt, rtol=1e-6, atol=1e-9):
        raise ValueError("hf_rms needs uniformly sampled data")
    x = x - x.mean(axis=0)
    spec = np.fft.rfft(x, axis=0)
    freq = np.fft.rfftfreq(n, dt)
    power = np.abs(spec) ** 2 / n**2
    power[1:] *= 2.0  # one-sided
    if n % 2 == 0:
        power[-1] /= 2.0  # the Nyquist bin is not doubled
    high = freq > cutoff_hz
    return float(math.sqrt(power[high].sum(axis=0).mean()))


def tilt_chattering_deg(t, euler_rad, euler_des_rad, cutoff_hz: float) -> float:
    """The chattering of a response as Figs. 12 and 15 show it: :func:`hf_rms` of the roll and
    pitch errors (deg), the attitude the controller sees minus the reference.

    Fig. 12 is "the results of quadrotor stabilization control", shown "to show the ability of
    the controllers in controlling the angles", whose "sharp peaks" mark the shocks; Fig. 15 "the
    controllers' response" to masses placed "to create uncertainties around the roll and pitch
    axis"; the paper shows the motors' commands only in Fig. 18 ("control input signals (thrust
    of each motor)"). The shocks and the masses act on roll and pitch.
    """
    err = np.degrees(np.asarray(euler_rad, dtype=float)[:, :2] - np.asarray(euler_des_rad, dtype=float)[:, :2])
    return hf_rms(t, err, cutoff_hz)


def divergence_time(t, euler_rad, limit_deg: float = DIVERGENCE_DEG) -> float | None:
    """First time |phi| or |theta| exceeds ``limit_deg`` (or the state is not finite); None if never."""
    t = np.asarray(t, dtype=float)
    e = np.asarray(euler_rad, dtype=float)[:, :2]
    bad = ~np.all(np.abs(e) <= math.radians(limit_deg), axis=1)
    idx = np.flatnonzero(bad)
    return float(t[idx[0]]) if idx.size else None


def window_mean_abs(t, a, b, t0: float, t1: float) -> float:
    """Mean of |a - b| over t0 <= t <= t1 (Eq. 45 on a window; ``b`` may be a number); NaN when empty."""
    t = np.asarray(t, dtype=float)
    sel = (t >= t0) & (t <= t1)
    a = np.asarray(a, dtype=float)
    b = np.broadcast_to(np.asarray(b, dtype=float), a.shape)  # b may be a constant reference
    d = np.abs(a[sel] - b[sel])
    d = d[np.isfinite(d)]
    return float(d.mean()) if d.size else math.nan


def mean_lag(t, actual, desired, *windows: tuple[float, float]) -> float:
    """Mean of (desired - actual) over the samples in any of the ``(t0, t1)`` windows (ends
    included): how far the response trails a rising reference."""
    t = np.asarray(t, dtype=float)
    sel = np.zeros(t.shape, dtype=bool)
    for t0, t1 in windows:
        sel |= (t >= t0) & (t <= t1)
    d = np.asarray(desired, dtype=float)[sel] - np.asarray(actual, dtype=float)[sel]
    d = d[np.isfinite(d)]
    return float(d.mean()) if d.size else math.nan


def improvement_pct(reference: float, new: float) -> float:
    """How much lower ``new`` is than ``reference``, in % of ``reference`` (negative: worse)."""
    if not reference or not math.isfinite(reference) or not math.isfinite(new):
        return math.nan
    return (reference - new) / reference * 100.0
