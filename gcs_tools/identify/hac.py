"""Covariance of a least-squares estimate whose residuals are autocorrelated (Newey-West / HAC).

Neighbouring samples of a flight log are not independent: the load cells' IIR filter, the random
torque's colour and any unmodelled dynamics correlate the residuals over tens of samples, and
``s^2 (J^T J)^-1`` then understates the uncertainty many times over. The heteroskedasticity- and
autocorrelation-consistent sandwich (Newey & West 1987, Bartlett kernel) does not assume
independence: ``cov = (J^T J)^-1 S (J^T J)^-1`` with ``S`` the long-run covariance of the scores
``s_t = J_t^T e_t``. It is the estimator statsmodels' ``OLS.fit(cov_type="HAC")`` computes; here
in a few lines of numpy on the scores of any residual vector (linear or not: the Jacobian of a
nonlinear fit at its optimum), so the motor fit and the torque regression share it without a
statsmodels dependency.
"""

from __future__ import annotations

import numpy as np


def long_run_covariance(scores: np.ndarray, lags: int) -> np.ndarray:
    """Bartlett-weighted long-run covariance of ``scores`` (T, k): ``G0 + sum (1 - l/(L+1)) (Gl + Gl^T)``."""
    s = np.asarray(scores, dtype=float)
    S = s.T @ s
    for lag in range(1, min(lags, s.shape[0] - 1) + 1):
        g = s[lag:].T @ s[:-lag]
        S += (1.0 - lag / (lags + 1.0)) * (g + g.T)
    return S


def hac_covariance(J: np.ndarray, e: np.ndarray, lags: int, groups: int = 1) -> np.ndarray:
    """Sandwich covariance of the parameters of residuals ``e`` (m,) with Jacobian ``J`` (m, k).

    ``groups``: the residual vector holds ``groups`` interleaved series sampled at the same times
    (row-major (T, groups)); their scores at one time are summed, so correlation between them at
    the same and neighbouring times is counted too.
    """
    J = np.asarray(J, dtype=float)
    e = np.asarray(e, dtype=float)
    scores = (J * e[:, None]).reshape(-1, groups, J.shape[1]).sum(axis=1)
    A = np.linalg.pinv(J.T @ J)
    return A @ long_run_covariance(scores, lags) @ A


def bandwidth(e: np.ndarray, dt: float, groups: int = 1, floor_s: float = 0.5) -> int:
    """Lags of the Bartlett window: twice the lag where the residuals' autocorrelation first falls
    below 0.1 (in samples), at least ``floor_s`` seconds: the window must span the correlation."""
    x = np.asarray(e, dtype=float).reshape(-1, groups)
    x = x - x.mean(axis=0)
    n = x.shape[0]
    f = np.fft.rfft(x, n=2 * n, axis=0)
    ac = np.fft.irfft(np.abs(f) ** 2, axis=0)[:n].sum(axis=1)
    ac = ac / ac[0] if ac[0] > 0 else ac
    below = np.nonzero(ac < 0.1)[0]
    first = int(below[0]) if below.size else n // 4
    return int(max(2 * first, round(floor_s / dt), 1))
