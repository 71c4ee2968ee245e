"""One form of the LMI of Eq. 32 for given gains: SDP solve, scipy cross-check, verdict and why.

The verdict rests on two independent computations: the cvxpy SDP (:mod:`.lmi`, its P
re-checked with numpy eigenvalues) and the Lyapunov equation (:mod:`.lyapunov_check`,
scipy). ``feasible`` needs both to find a positive-definite P; ``infeasible`` needs the
SDP to find no P with a positive infeasibility measure t*, scipy to find no
positive-definite P, and an unstable eigenpair of F, which explains it. Any disagreement
gives ``undecided``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs_tools.stability.error_dynamics import dynamics
from gcs_tools.stability.lmi import LmiSolution, solve_lmi
from gcs_tools.stability.lyapunov_check import ScipyCheck, UnstableMode, scipy_check, unstable_modes
from gcs_tools.stability.settings import Settings

VERDICTS = ("feasible", "infeasible", "undecided")


@dataclass(frozen=True)
class FormResult:
    form: str  # "derived" (A = N - h kappa) or "printed" (Eq. 32 as printed)
    F: np.ndarray
    f_eigenvalues: np.ndarray  # eig(F), sorted by real part then imaginary part
    sdp: LmiSolution
    scipy: ScipyCheck
    unstable: list[UnstableMode]
    verdict: str

    @property
    def feasible(self) -> bool:
        return self.verdict == "feasible"

    def explanation(self) -> str:
        """Plain-language reason for the verdict, from the computed numbers."""
        if self.verdict == "feasible":
            return (
                f"feasible: the SDP ({self.sdp.solver}, status {self.sdp.status}) found P with "
                f"min eig(P) = {self.sdp.p_eigenvalues[0]:.6g} > 0 and max eig(F^T P + P F) = "
                f"{self.sdp.lmi_max_eigenvalue:.6g} < 0 (checked with numpy); scipy's Lyapunov solution is "
                f"positive definite (min eig {self.scipy.p0_eigenvalues[0]:.6g}); every eigenvalue of F has a "
                f"negative real part (max {self.f_eigenvalues.real.max():.6g} 1/s)."
            )
        sdp = self.sdp
        if sdp.verified:
            found = (f"the SDP ({sdp.solver}, status {sdp.status}) found a P verified by numpy "
                     f"(max eig(F^T P + P F) = {sdp.lmi_max_eigenvalue:.6g})")
        elif sdp.best_max_eigenvalue is not None:
            found = (f"the SDP with margins found no P (status {sdp.status}, {sdp.solver}); the bounded SDP gives "
                     f"t* = min over I <= P <= {sdp.cap:g} I of max eig(F^T P + P F) = {sdp.best_max_eigenvalue:.6g} "
                     f"(status {sdp.best_status})")
        else:
            found = (f"the SDP with margins found no P (status {sdp.status}, {sdp.solver}) and the bounded SDP no "
                     f"optimum (status {sdp.best_status})")
        lines = [
            f"{self.verdict}: {found}; scipy's Lyapunov solution is "
            + ("positive definite" if self.scipy.feasible else "not positive definite or not found")
            + f"; max Re eig(F) = {self.f_eigenvalues.real.max():.6g} 1/s"
            + (f", and t* >= 2 max Re(lambda) = {2.0 * max(m.eigenvalue.real for m in self.unstable):.6g} as it must be."
               if self.unstable and sdp.best_max_eigenvalue is not None else ".")
        ]
        for m in self.unstable:
            lines.append(
                f"{m.axis}: s^2 + ({m.c1:.6g}) s + ({m.c0:.6g}) has the root {_fmt(m.eigenvalue)} 1/s with "
                f"Re >= 0; {m.reason}. For its eigenvector v, v^H (F^T P + P F) v = 2 Re(lambda) v^H P v >= 0 "
                "for every P > 0, so no P satisfies the LMI."
            )
        return "\n".join(lines)


def _fmt(z: complex) -> str:
    return f"{z.real:.6g}" if z.imag == 0.0 else f"{z.real:.6g}{z.imag:+.6g}j"


def _sorted_eigenvalues(F: np.ndarray) -> np.ndarray:
    ev = np.linalg.eigvals(F)
    return ev[np.lexsort((ev.imag, ev.real))]


def check_form(form: str, h: np.ndarray, kappa: np.ndarray, settings: Settings) -> FormResult:
    """Solve and cross-check the ``form`` (``derived`` or ``printed``) of Eq. 32 for ``kappa``."""
    F = dynamics(form, h, kappa)
    margin = settings.lmi_margin
    sdp = solve_lmi(F, margin, settings.lmi_p_floor, settings.lmi_solver, settings.lmi_condition_cap)
    sp = scipy_check(F, margin)
    modes = unstable_modes(F, form)
    if sdp.verified and sp.feasible and not modes:
        verdict = "feasible"
    elif sdp.solver_says_infeasible and not sp.feasible and modes:
        verdict = "infeasible"
    else:
        verdict = "undecided"
    return FormResult(form, F, _sorted_eigenvalues(F), sdp, sp, modes, verdict)
