"""The paper's published stability figures, as printed: kappa of Eq. 42, P and its eigenvalues of Eq. 43.

The paper states no units for them, nor the range over which the planes were fitted.
Eq. 43's P is printed non-symmetric; its listed eigenvalues are those of the printed
(non-symmetric) matrix. Kept verbatim so that the report can compare and check them.
"""

from __future__ import annotations

import numpy as np

#: Table 3: d1 of the error (deg) and of the error rate (deg/s) per axis, phi, theta, psi.
TABLE3_D1 = ((1.8, 7.0), (1.8, 7.0), (2.5, 5.0))

#: Eq. 42: fitted (kp, kd) per axis, phi, theta, psi.
KAPPA_GAINS = ((9.8, 6.7), (9.8, 6.7), (6.3, 9.2))

#: Eq. 43: P as printed (rows as printed; not symmetric).
P_PRINTED = (
    (0.364, 0.327, 0.0, 0.0, 0.0, 0.0),
    (0.178, 0.175, 0.0, 0.0, 0.0, 0.0),
    (0.0, 0.0, 0.332, 0.349, 0.0, 0.0),
    (0.0, 0.0, 0.111, 0.159, 0.0, 0.0),
    (0.0, 0.0, 0.0, 0.0, 0.243, 0.438),
    (0.0, 0.0, 0.0, 0.0, 0.278, 0.527),
)

#: Eq. 43: the eigenvalues lambda_1..lambda_6 as printed.
P_EIGENVALUES = (0.008, 0.010, 0.031, 0.460, 0.529, 0.763)


def kappa_matrix(gains=KAPPA_GAINS) -> np.ndarray:
    """The 3 x 6 matrix of Eq. 20 from per-axis ``(kp, kd)`` pairs (Eq. 42 by default)."""
    gains = np.asarray(gains, dtype=np.float64)
    if gains.shape != (3, 2):
        raise ValueError("need three (kp, kd) pairs: phi, theta, psi")
    kappa = np.zeros((3, 6))
    for k in range(3):
        kappa[k, 2 * k : 2 * k + 2] = gains[k]
    return kappa
