"""The ultimate bound R2 of Eq. 31 (from Eq. 25-30).

Eq. 31: ``R2 = (sigma_max(P) |g_max| + sigma_max(P h) |d*|) / sigma_min(H)`` with
``H = -(A^T P + P A)`` (Eq. 26, sign as derived) and ``|e|`` the Euclidean norm of the
6-vector of angle (rad) and rate (rad/s) errors, so R2 has those mixed units.

Two things the printed derivation drops are computed alongside:

* Eq. 22 carries a factor 1/2 (``V = e^T P e / 2``), so ``V' <= -sigma_min(H) |e|^2 / 2 +
  ...``, and V1 of Eq. 29 vanishes at twice Eq. 31's radius: ``R2_derived = 2 R2``.
* V' < 0 outside the ball ``|e| <= R2_derived`` confines e to the smallest level set of V
  containing that ball, of radius ``R2_derived sqrt(lambda_max(P) / lambda_min(P))``: the
  ultimate bound on ``|e|``. The plane-plus-residual model only holds inside the fit
  rectangle, so that radius is compared with the rectangle's smallest half-width.

``|d*|`` is the norm of the per-axis maxima of ``|u - u_est|`` over the fit rectangle:
the whole residual is treated as the bounded estimation error, so the argument does not
need the sign assumption on d of Eq. 17 and 26 (S >= 0), which the fit may violate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class UltimateBound:
    g_max: np.ndarray  # Eq. 27, rad/s^2, 6 entries
    g_max_norm: float
    d_star_norm: float  # N m
    sigma_max_P: float
    sigma_max_Ph: float
    sigma_min_H: float
    r2: float  # Eq. 31 as printed
    r2_derived: float  # with the 1/2 of Eq. 22 kept
    ultimate_bound: float  # r2_derived sqrt(cond(P))
    region_radius: float  # smallest half-width of the fit rectangle (rad or rad/s)

    @property
    def inside_region(self) -> bool:
        return self.ultimate_bound <= self.region_radius


def r2_eq31(sigma_max_P: float, g_max_norm: float, sigma_max_Ph: float, d_star_norm: float, sigma_min_H: float) -> float:
    """Eq. 31 as printed."""
    if not sigma_min_H > 0.0:
        raise ValueError("sigma_min(H) must be positive (H > 0 is the second line of Eq. 32)")
    return (sigma_max_P * g_max_norm + sigma_max_Ph * d_star_norm) / sigma_min_H


def ultimate_bound(P: np.ndarray, A: np.ndarray, h: np.ndarray, g_max: np.ndarray, d_star, region_radius: float) -> UltimateBound:
    """Eq. 27-31 for a P solving the LMI of the closed-loop matrix ``A = N - h kappa``."""
    P = np.asarray(P, dtype=np.float64)
    H = -(A.T @ P + P @ A)
    H = 0.5 * (H + H.T)
    sv_P = np.linalg.svd(P, compute_uv=False)
    sv_Ph = np.linalg.svd(P @ h, compute_uv=False)
    sv_H = np.linalg.svd(H, compute_uv=False)
    h_eig = np.linalg.eigvalsh(H)
    if h_eig[0] <= 0.0:
        raise ValueError("H = -(A^T P + P A) is not positive definite: P does not solve Eq. 32")
    g = np.asarray(g_max, dtype=np.float64)
    g_norm = float(np.linalg.norm(g))
    d_norm = float(np.linalg.norm(np.asarray(d_star, dtype=np.float64)))
    r2 = r2_eq31(float(sv_P[0]), g_norm, float(sv_Ph[0]), d_norm, float(sv_H[-1]))
    p_eig = np.linalg.eigvalsh(P)
    r2_derived = 2.0 * r2
    return UltimateBound(
        g_max=g, g_max_norm=g_norm, d_star_norm=d_norm, sigma_max_P=float(sv_P[0]),
        sigma_max_Ph=float(sv_Ph[0]), sigma_min_H=float(sv_H[-1]), r2=r2, r2_derived=r2_derived,
        ultimate_bound=float(r2_derived * np.sqrt(p_eig[-1] / p_eig[0])), region_radius=float(region_radius),
    )
