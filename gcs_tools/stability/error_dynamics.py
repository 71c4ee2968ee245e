"""Closed-loop attitude error dynamics of the FLC (Eq. 18-26, Eq. A10) and the two readings of Eq. 32.

State ``e = x_des - x`` with ``x = [phi, phi', theta, theta', psi, psi']`` (Eq. A10).
The simplified hover model is ``x' = g(x) + h u`` with ``h`` of Eq. A10 and
``g = g1 + N x`` (Eq. 23, ``N`` of Eq. 24). With ``u = kappa e + d + d*`` (Eq. 18) the
error obeys (Eq. 19 with Eq. 23)::

    e' = (N - h kappa) e + (g1* - g1) - h d - h d*

so the linear part is ``A = N - h kappa`` and ``V = e^T P e / 2`` (Eq. 21) decreases for
``d = d* = g1* - g1 = 0`` iff ``A^T P + P A < 0``, i.e. ``P h kappa + kappa^T h^T P - P N
- N^T P > 0``. Eq. 25, 26 and 32 print this matrix with ``+ P N + N^T P``. Both forms are
written here as a Lyapunov inequality ``F^T P + P F < 0``:

* derived (from Eq. 19, 22, 23): ``F = A = N - h kappa``;
* as printed (Eq. 32): ``P (h kappa + N) + (h kappa + N)^T P > 0``, i.e. ``F = -(h kappa + N)``.
"""

from __future__ import annotations

import numpy as np

#: Eq. 24.
N_MATRIX = np.zeros((6, 6))
N_MATRIX[0, 1] = N_MATRIX[2, 3] = N_MATRIX[4, 5] = 1.0
N_MATRIX.setflags(write=False)

FORMS = ("derived", "printed")


def h_matrix(ixx: float, iyy: float, izz: float) -> np.ndarray:
    """``h`` of Eq. A10 (6 x 3): ``1/Ixx``, ``1/Iyy``, ``1/Izz`` on the rate rows."""
    for name, v in (("ixx", ixx), ("iyy", iyy), ("izz", izz)):
        if not (np.isfinite(v) and v > 0.0):
            raise ValueError(f"{name} = {v!r}: inertia must be positive")
    h = np.zeros((6, 3))
    h[1, 0], h[3, 1], h[5, 2] = 1.0 / ixx, 1.0 / iyy, 1.0 / izz
    return h


def check_kappa(kappa) -> np.ndarray:
    """``kappa`` as a finite 3 x 6 array with the block structure of Eq. 20 (ValueError otherwise)."""
    kappa = np.asarray(kappa, dtype=np.float64)
    if kappa.shape != (3, 6) or not np.all(np.isfinite(kappa)):
        raise ValueError("kappa must be a finite 3 x 6 matrix (Eq. 20)")
    mask = np.zeros((3, 6), dtype=bool)
    for k in range(3):
        mask[k, 2 * k : 2 * k + 2] = True
    if np.any(kappa[~mask] != 0.0):
        raise ValueError("kappa must have the block structure of Eq. 20 (axis k acts on e[2k], e[2k+1] only)")
    return kappa


def dynamics(form: str, h: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    """``F`` of the Lyapunov inequality ``F^T P + P F < 0`` for the ``derived`` or ``printed`` form."""
    hk = h @ check_kappa(kappa)
    if form == "derived":
        return N_MATRIX - hk
    if form == "printed":
        return -(hk + N_MATRIX)
    raise ValueError(f"form must be one of {FORMS}")


def lmi_matrix(form: str, P: np.ndarray, h: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    """The matrix Eq. 32 requires to be positive definite, ``H = -(F^T P + P F)`` (Eq. 26's H for the form)."""
    F = dynamics(form, h, kappa)
    return -(F.T @ P + P @ F)


def axis_block(F: np.ndarray, k: int) -> np.ndarray:
    """The 2 x 2 block of axis ``k`` (0 phi, 1 theta, 2 psi); F is block-diagonal by Eq. 20 and 24."""
    return F[2 * k : 2 * k + 2, 2 * k : 2 * k + 2]


def characteristic(block: np.ndarray) -> tuple[float, float]:
    """``(c1, c0)`` of ``s^2 + c1 s + c0``, the characteristic polynomial of a 2 x 2 block.

    The block is Hurwitz iff ``c1 > 0`` and ``c0 > 0``. For ``F = N - h kappa`` on one axis
    ``c1 = kd / I`` and ``c0 = kp / I``; for the printed form ``c0 = -kp / I``.
    """
    return float(-np.trace(block)), float(np.linalg.det(block))


def g_max(ixx: float, iyy: float, izz: float, desired_rate_max, rate_error_max) -> np.ndarray:
    """Componentwise bound of ``g1* - g1`` (Eq. 27) from the gyroscopic terms of Eq. A10.

    ``g1 = [0, c_phi theta' psi', 0, c_theta phi' psi', 0, c_psi phi' theta']`` with
    ``c_phi = (Iyy - Izz)/Ixx``, ``c_theta = (Izz - Ixx)/Iyy``, ``c_psi = (Ixx - Iyy)/Izz``.
    Desired rates are bounded by ``desired_rate_max`` and actual ones by
    ``desired_rate_max + rate_error_max`` (``x' = x_des' - e'``), all in rad/s, so
    ``|g1*_i - g1_i| <= |c_i| (wd_a wd_b + w_a w_b)``.
    """
    wd = np.asarray(desired_rate_max, dtype=np.float64)
    w = wd + np.asarray(rate_error_max, dtype=np.float64)
    if wd.shape != (3,) or w.shape != (3,) or np.any(wd < 0.0) or np.any(w < 0.0):
        raise ValueError("rate bounds must be three non-negative numbers (phi, theta, psi)")
    c = (abs(iyy - izz) / ixx, abs(izz - ixx) / iyy, abs(ixx - iyy) / izz)
    pairs = ((1, 2), (0, 2), (0, 1))
    out = np.zeros(6)
    for k, (a, b) in enumerate(pairs):
        out[2 * k + 1] = c[k] * (wd[a] * wd[b] + w[a] * w[b])
    return out
