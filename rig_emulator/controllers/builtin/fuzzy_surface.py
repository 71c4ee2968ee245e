"""Control-surface analysis of an FLC axis: the fitted plane of Eq. 16 and its residual, Eq. 17.

The stability analysis of Sec. 3-2 (Eq. 16-32) replaces the FLC surface ``u(e, de)`` by a
plane through the origin ``u_est = kp e + kd de`` (Eq. 16, Fig. 6) plus a residual
``d = (u - u_est) sgn(e)`` (Eq. 17) that enters Eq. 18 and the ultimate bound of Eq. 31.

Units: everything is in the caller's units. The paper's fitted gains (Eq. 42:
phi (kp, kd) = (9.8, 6.7), theta (9.8, 6.7), psi (6.3, 9.2)) state no units, nor the
range of ``e``, ``de`` the planes were fitted over, so they cannot be reproduced exactly;
fit in the units (rad or deg) and over the range you need and compare with care.
Reading: "least squares over a uniform grid of the rectangle ``|e| <= e_max``,
``|de| <= de_max``" is the fit adopted here.

Python-side analysis code (numpy); the surface itself is evaluated by the compiled
:func:`rig_emulator.controllers.builtin.fuzzy.flc_eval_many`.
"""

from __future__ import annotations

import numpy as np

from rig_emulator.controllers.builtin.fuzzy import RULE_TABLE, FuzzyAxis, flc_eval_many


def control_surface(
    axis: FuzzyAxis, e_max: float, de_max: float, n: int = 41, rule_table=RULE_TABLE
):
    """The FLC surface on an ``n x n`` grid of ``[-e_max, e_max] x [-de_max, de_max]`` (Fig. 6).

    Returns ``(E, DE, U)``, each of shape ``(n, n)`` with ``indexing="ij"``: ``E[a, b]`` is
    the a-th error value, ``DE[a, b]`` the b-th error-rate value, ``U`` the FLC output.
    """
    if n < 2:
        raise ValueError("n must be at least 2")
    e = np.linspace(-float(e_max), float(e_max), n)
    de = np.linspace(-float(de_max), float(de_max), n)
    E, DE = np.meshgrid(e, de, indexing="ij")
    flat_e = np.ascontiguousarray(E.ravel())
    flat_de = np.ascontiguousarray(DE.ravel())
    out = np.empty_like(flat_e)
    flc_eval_many(
        flat_e, flat_de, axis.e_terms, axis.de_terms, axis.out_centers,
        np.asarray(rule_table, dtype=np.int64), out,
    )
    return E, DE, out.reshape(E.shape)


def fit_plane(E, DE, U):
    """Least-squares plane through the origin, ``u_est = kp e + kd de`` (Eq. 16): ``(kp, kd)``."""
    A = np.column_stack((np.ravel(E), np.ravel(DE))).astype(np.float64)
    coef, *_ = np.linalg.lstsq(A, np.ravel(U).astype(np.float64), rcond=None)
    return float(coef[0]), float(coef[1])


def plane_residual(E, DE, U, kp: float, kd: float):
    """Residual of Eq. 17, ``d = (u - (kp e + kd de)) sgn(e)``, and its largest magnitude.

    Returns ``(d, d_max)`` with ``d`` shaped like ``U``. ``sgn(0) = 0``. The paper's
    argument (Eq. 26, 30) assumes ``d`` has the sign of ``e``, i.e. ``d >= 0``; check
    ``d.min()`` to see whether a fitted plane satisfies it.
    """
    E = np.asarray(E, dtype=np.float64)
    u_est = kp * E + kd * np.asarray(DE, dtype=np.float64)
    d = (np.asarray(U, dtype=np.float64) - u_est) * np.sign(E)
    return d, float(np.max(np.abs(d)))
