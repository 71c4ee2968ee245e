"""Fitted planes of the FLC control surfaces (Eq. 16), their residual (Eq. 17) and kappa (Eq. 20).

Per attitude axis the FLC surface ``u(e, de)`` the rig flies is sampled over a rectangle
and a plane through the origin ``u_est = kp e + kd de`` is fitted by least squares
(:func:`rig_emulator.controllers.builtin.fuzzy_surface.fit_plane`). SI throughout: e in rad, de in
rad/s, u in N m, so kp is in N m/rad and kd in N m s/rad.

Reading (the paper gives no fit range): the rectangle is ``|e| <= scale e_sat``,
``|de| <= scale de_sat`` where ``e_sat`` is the input beyond which the FLC output stops
changing (:func:`saturation_edge`), i.e. the whole non-saturated surface for ``scale = 1``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rig_emulator.controllers.builtin.fuzzy import TERM_CENTER, TERM_RIGHT_HALF_WIDTH, TERM_SHOULDER, FuzzyAxis
from rig_emulator.controllers.builtin.fuzzy_surface import control_surface, fit_plane, plane_residual

AXES = ("phi", "theta", "psi")


@dataclass(frozen=True)
class AxisPlane:
    """One axis of Eq. 16-17: the fitted gains and what the residual looks like over the fit rectangle."""

    axis: str
    kp: float  # N m / rad
    kd: float  # N m s / rad
    e_max: float  # rad, half-width of the fit rectangle in e
    de_max: float  # rad/s, half-width in de
    residual_max: float  # N m, max |u - u_est| over the grid (bounds d* of Eq. 18)
    d_min: float  # N m, min of d = (u - u_est) sgn(e) (Eq. 17); < 0 breaks the paper's sign assumption
    d_negative_fraction: float  # share of grid points with d < 0
    grid_points: int


def saturation_edge(terms: np.ndarray) -> float:
    """Input beyond which only the outer shoulder term fires, so the FLC output stops changing.

    The largest right edge ``center + right half-width`` of the non-shoulder input terms
    (``d1 + d2 + dt`` for the paper's geometry, ``3 d1`` for the even one).
    """
    inner = terms[terms[:, TERM_SHOULDER] == 0.0]
    return float(np.max(inner[:, TERM_CENTER] + inner[:, TERM_RIGHT_HALF_WIDTH]))


def fit_axis(name: str, axis: FuzzyAxis, scale: float, n: int) -> AxisPlane:
    """Eq. 16-17 for one axis over the rectangle ``scale x`` the saturation edges, ``n x n`` points."""
    e_max = scale * saturation_edge(axis.e_terms)
    de_max = scale * saturation_edge(axis.de_terms)
    E, DE, U = control_surface(axis, e_max, de_max, n)
    kp, kd = fit_plane(E, DE, U)
    d, d_abs_max = plane_residual(E, DE, U, kp, kd)
    return AxisPlane(
        axis=name, kp=kp, kd=kd, e_max=e_max, de_max=de_max, residual_max=d_abs_max,
        d_min=float(d.min()), d_negative_fraction=float(np.mean(d < 0.0)), grid_points=n,
    )


def kappa_of(planes) -> np.ndarray:
    """The 3 x 6 kappa of Eq. 20 from the three fitted planes (phi, theta, psi)."""
    kappa = np.zeros((3, 6))
    for k, p in enumerate(planes):
        kappa[k, 2 * k] = p.kp
        kappa[k, 2 * k + 1] = p.kd
    return kappa
