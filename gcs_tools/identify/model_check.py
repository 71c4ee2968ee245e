"""Does the model explain the log? Residuals judged, window by window, against what the noise alone leaves.

Two channels, each cut into windows of :data:`WINDOW_S` seconds:

* ``torque roll/pitch/yaw``: the torque balance's residual (gcs_tools/identify/torque_balance.py), each
  window **predicted by a fit that did not see it** (the regression refitted without the window: a
  held-out test, cheap because the balance is linear). Its mean square is compared with what the noise
  model says it should be there, ``kappa sigma^2 L^2`` (the random torque at the window's rotor load)
  plus the load cells' own noise, the variance of the prediction itself (large where the window alone
  carries an effect, as the yaw spin-down carries the yaw friction) and a floor :data:`FLOOR_VAR`. Where the motors are stopped (the swings) that expectation is the
  load cells' floor alone, so an unmodelled friction or pendulum shows at once;
* ``load cell 1..4``: the motor chain's residual (gcs_tools/identify/motor_chain.py) against the load
  cells' own filtered noise, relative to the median window of the same cell (the chain's commands are
  logged at the log rate, so even a matched chain leaves some residual everywhere; a wrong chain leaves
  more in some windows, e.g. at low thrust where a thrust bias shows).

A window whose ratio is above :data:`TORQUE_LIMIT` (torque) or :data:`CELL_LIMIT` (cells) is reported,
with its channel and time; the limits were set on the calibration study's matched draws (none of them
flagged) and checked on its mismatched ones (``rig-gcs identify --calibration-study``, docs/how-to/identify.md).
A whiteness check completes it: the autocorrelation of the torque residual at lags of 0.5-2 s, where the
noise model (a 2 Hz process behind a 2 Hz filter) leaves almost none; a slow unmodelled effect leaves a lot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WINDOW_S = 5.0
# what the attitude estimate's error (a few tenths of a degree, on a pendulum of m g r_z = 0.8 N m) and a
# window's own share of the parameters' information leave in a held-out window even with the right model
FLOOR_VAR = np.array([0.006, 0.006, 0.003]) ** 2  # N^2 m^2
TORQUE_LIMIT = 6.0
CELL_LIMIT = 8.0
WHITE_LAG_S = (0.5, 2.0)
WHITE_LIMIT = 0.5


@dataclass
class Finding:
    channel: str
    t_from: float
    t_to: float
    ratio: float
    limit: float

    def text(self) -> str:
        return (f"{self.channel}: t = {self.t_from:.0f}-{self.t_to:.0f} s, residual {self.ratio:.1f}x what the noise "
                f"explains (limit {self.limit:g}x)")


def _windows(t: np.ndarray):
    edges = np.arange(np.floor(t[0]), t[-1] + WINDOW_S, WINDOW_S)
    for a, b in zip(edges[:-1], edges[1:]):
        yield a, b, (t >= a) & (t < b)


def torque_findings(log, held_out: np.ndarray, expected_var: np.ndarray, used: np.ndarray,
                    prediction_var: np.ndarray | None = None, fitted: np.ndarray | None = None) -> tuple[list, dict]:
    """``held_out`` (n, 3): residuals of each window predicted by the fit without it; ``expected_var`` (n, 3)
    what the noise leaves; ``prediction_var`` (n, 3) the variance of that prediction itself; ``fitted``
    (n, 3) the residuals of the fit with every window, judged against the noise alone: where one window
    carries an effect (the swings, the friction) the held-out prediction is loose, but a model that lacks
    the effect cannot fit that window even with it."""
    out = []
    worst = {}
    pv = np.zeros_like(expected_var) if prediction_var is None else np.nan_to_num(prediction_var)
    for a, b, w in _windows(log.t):
        w = w & used
        if w.sum() < 50:
            continue
        for ax, name in enumerate(("torque roll", "torque pitch", "torque yaw")):
            noise = np.mean(expected_var[w, ax]) + FLOOR_VAR[ax]
            ratios = [(name, float(np.mean(held_out[w, ax] ** 2) / (noise + np.mean(pv[w, ax]))))]
            if fitted is not None:
                ratios.append((name + " (fitted)", float(np.mean(fitted[w, ax] ** 2) / noise)))
            for label, ratio in ratios:
                worst[label] = max(worst.get(label, 0.0), ratio)
                if ratio > TORQUE_LIMIT:
                    out.append(Finding(label, a, b, ratio, TORQUE_LIMIT))
    return out, worst


def cell_findings(log, resid: np.ndarray, noise_var: np.ndarray, used: np.ndarray) -> tuple[list, dict]:
    ratios = []
    for a, b, w in _windows(log.t):
        w = w & used
        if w.sum() < 50:
            continue
        ratios.append((a, b, np.mean(resid[w] ** 2, axis=0) / np.mean(noise_var[w], axis=0)))
    out = []
    worst = {}
    if not ratios:
        return out, worst
    med = np.median(np.array([r for _, _, r in ratios]), axis=0)
    for a, b, r in ratios:
        for i in range(4):
            ratio = float(r[i] / med[i])
            name = f"load cell {i + 1}"
            worst[name] = max(worst.get(name, 0.0), ratio)
            if ratio > CELL_LIMIT:
                out.append(Finding(name, a, b, ratio, CELL_LIMIT))
    return out, worst


def whiteness(resid: np.ndarray, used: np.ndarray, dt: float) -> dict:
    """Mean autocorrelation of each torque axis's residual over lags :data:`WHITE_LAG_S` (contiguous rows)."""
    out = {}
    lo, hi = (int(round(x / dt)) for x in WHITE_LAG_S)
    for ax, name in enumerate(("torque roll", "torque pitch", "torque yaw")):
        x = np.where(used, resid[:, ax], 0.0)
        x = x - x[used].mean()
        x[~used] = 0.0
        n = x.size
        f = np.fft.rfft(x, n=2 * n)
        ac = np.fft.irfft(np.abs(f) ** 2)[:n]
        out[name] = float(np.mean(ac[lo:hi]) / ac[0]) if ac[0] > 0 else 0.0
    return out
