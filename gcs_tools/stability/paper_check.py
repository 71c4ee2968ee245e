"""Does the paper's own P (Eq. 43) satisfy Eq. 32 with the paper's kappa (Eq. 42)?

``V = e^T P e / 2`` (Eq. 21) only sees the symmetric part ``(P + P^T) / 2`` of the printed,
non-symmetric P, so positivity is checked on that part; the LMI of each form is evaluated
with it and the rig's inertia (h of Eq. A10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs_tools.stability import paper_values
from gcs_tools.stability.error_dynamics import FORMS, dynamics


@dataclass(frozen=True)
class PaperPCheck:
    symmetric: bool  # is the printed P symmetric
    eig_printed: np.ndarray  # eigenvalues of the printed matrix (real parts, ascending): Eq. 43's list
    eig_symmetric_part: np.ndarray  # eigenvalues of (P + P^T)/2, ascending: what V sees
    lmi_max_eigenvalue: dict  # form -> max eig(F^T S + S F) with S the symmetric part (< 0 needed)

    @property
    def positive_definite(self) -> bool:
        return bool(self.eig_symmetric_part[0] > 0.0)

    def satisfies(self, form: str) -> bool:
        return self.positive_definite and self.lmi_max_eigenvalue[form] < 0.0


def check_paper_p(h: np.ndarray) -> PaperPCheck:
    P = np.array(paper_values.P_PRINTED)
    S = 0.5 * (P + P.T)
    kappa = paper_values.kappa_matrix()
    lmi = {}
    for form in FORMS:
        F = dynamics(form, h, kappa)
        lmi[form] = float(np.max(np.linalg.eigvalsh(F.T @ S + S @ F)))
    return PaperPCheck(
        symmetric=bool(np.array_equal(P, P.T)),
        eig_printed=np.sort(np.linalg.eigvals(P).real),
        eig_symmetric_part=np.linalg.eigvalsh(S),
        lmi_max_eigenvalue=lmi,
    )
