"""Solver-independent checks of Eq. 32: the Lyapunov equation (scipy) and unstable-mode certificates.

* ``F^T P + P F < 0`` with ``P > 0`` has a solution iff every eigenvalue of F has a negative
  real part (Lyapunov's theorem). scipy's ``solve_continuous_lyapunov`` gives the P0 of
  ``F^T P0 + P0 F = -margin I``; it is positive definite exactly when F is Hurwitz.
* An eigenpair ``F v = lambda v`` with ``Re(lambda) >= 0`` proves infeasibility for every P:
  ``v^H (F^T P + P F) v = 2 Re(lambda) v^H P v >= 0`` for every ``P > 0``. Such pairs are
  reported with the axis they belong to and the coefficient of the axis' characteristic
  polynomial (Hurwitz test ``c1 > 0, c0 > 0``) that fails.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import LinAlgError, solve_continuous_lyapunov

from gcs_tools.stability.error_dynamics import axis_block, characteristic
from gcs_tools.stability.planes import AXES


@dataclass(frozen=True)
class ScipyCheck:
    """``F^T P0 + P0 F = -margin I`` solved with scipy."""

    P0: np.ndarray | None
    p0_eigenvalues: np.ndarray | None
    residual: float | None  # max |F^T P0 + P0 F + margin I|
    hurwitz: bool  # max Re eig(F) < 0
    feasible: bool  # P0 exists, is positive definite and solves the equation


@dataclass(frozen=True)
class UnstableMode:
    """An eigenpair of F with ``Re(lambda) >= 0``: a certificate that Eq. 32 has no solution."""

    axis: str
    eigenvalue: complex
    vector: np.ndarray  # unit eigenvector (6 entries, complex)
    c1: float  # s^2 + c1 s + c0 of the axis block
    c0: float
    reason: str


def scipy_check(F: np.ndarray, margin: float) -> ScipyCheck:
    F = np.asarray(F, dtype=np.float64)
    eye = np.eye(F.shape[0])
    hurwitz = bool(np.max(np.linalg.eigvals(F).real) < 0.0)
    try:
        P0 = solve_continuous_lyapunov(F.T, -margin * eye)
    except (LinAlgError, ValueError):
        return ScipyCheck(None, None, None, hurwitz, False)
    if not np.all(np.isfinite(P0)):
        return ScipyCheck(None, None, None, hurwitz, False)
    P0 = 0.5 * (P0 + P0.T)
    eig = np.linalg.eigvalsh(P0)
    residual = float(np.max(np.abs(F.T @ P0 + P0 @ F + margin * eye)))
    feasible = bool(eig[0] > 0.0 and residual <= 1e-8 * margin * max(1.0, float(np.max(np.abs(P0)))))
    return ScipyCheck(P0, eig, residual, hurwitz, feasible)


def _reason(c1: float, c0: float, form: str) -> str:
    kp_term = "kp/I" if form == "derived" else "-kp/I (the + P N + N^T P of Eq. 32 as printed)"
    parts = []
    if c0 <= 0.0:
        parts.append(f"c0 = {c0:.6g} 1/s^2 <= 0 (c0 = {kp_term}): the error feedback e has the wrong sign")
    if c1 <= 0.0:
        parts.append(f"c1 = {c1:.6g} 1/s <= 0 (c1 = kd/I): the rate feedback de gives no damping")
    return "; ".join(parts)


def unstable_modes(F: np.ndarray, form: str) -> list[UnstableMode]:
    """Every eigenpair of F with ``Re(lambda) >= 0``, by axis (F is block-diagonal, Eq. 20 and 24)."""
    modes = []
    for k, name in enumerate(AXES):
        block = axis_block(F, k)
        c1, c0 = characteristic(block)
        values, vectors = np.linalg.eig(block)
        for j in np.argsort(-values.real, kind="stable"):
            lam = complex(values[j])
            if lam.real < 0.0:
                continue
            v = np.zeros(6, dtype=complex)
            v[2 * k : 2 * k + 2] = vectors[:, j]
            v /= np.linalg.norm(v)
            modes.append(UnstableMode(name, lam, v, c1, c0, _reason(c1, c0, form)))
    return modes
