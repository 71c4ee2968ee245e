"""The LMI of Eq. 32 solved numerically with cvxpy (optional extra ``analysis``).

Eq. 32 asks for ``P > 0`` and ``H > 0``; with ``H = -(F^T P + P F)``
(:mod:`gcs_tools.stability.error_dynamics`) it is posed with margins as the SDP::

    minimise trace(P)  subject to  P >= p_floor I,  F^T P + P F <= -margin I

The LMI is homogeneous in P, so ``margin`` only fixes the scale. The trace objective makes
the answer unique: when F is Hurwitz every feasible P satisfies ``P >= P0`` with P0 the
solution of ``F^T P0 + P0 F = -margin I``, so the SDP returns P0 (which the scipy
cross-check computes independently), and P0 also minimises ``sigma_max(P) /
sigma_min(H)``, the factor of the ultimate bound of Eq. 31. Whatever the solver says,
the reported P is re-checked with numpy eigenvalues.

When that SDP finds no P (reported infeasible, or the solver stops), a bounded problem
that is always feasible measures how far the LMI is from feasibility::

    t* = minimise t  subject to  I <= P <= cap I,  F^T P + P F <= t I

(F scaled by its spectral norm for the solver, t* scaled back). ``t* > 0`` means no P with
condition number up to ``cap`` satisfies the LMI; for an eigenpair ``F v = lambda v`` with
``Re(lambda) >= 0``, ``t* >= 2 Re(lambda)`` must hold, which the report shows.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from gcs_tools.errors import OperationError

INSTALL_HINT = "pip install -e '.[analysis]'  (or: pip install 'cvxpy-base>=1.5,<2' 'clarabel>=0.9,<1')"


class AnalysisUnavailable(OperationError):
    """cvxpy (or the chosen solver) is not installed."""


@dataclass(frozen=True)
class LmiSolution:
    """What the SDP solver returned for one form of Eq. 32, re-checked independently."""

    status: str  # cvxpy's status string for the SDP with margins
    solver: str
    P: np.ndarray | None  # symmetrised solution, None unless the solver found one
    p_eigenvalues: np.ndarray | None  # eig(P), ascending
    lmi_max_eigenvalue: float | None  # max eig(F^T P + P F): must be < 0
    verified: bool  # P > 0 and F^T P + P F < 0 by numpy eigenvalues, with half the margins
    best_status: str | None = None  # status of the bounded problem (only run when not verified)
    best_max_eigenvalue: float | None = None  # its t*: min over I <= P <= cap I of max eig(F^T P + P F)
    cap: float | None = None

    @property
    def solver_says_infeasible(self) -> bool:
        """The SDP found no P and the bounded problem's optimum t* is positive."""
        return (
            not self.verified
            and self.best_status in ("optimal", "optimal_inaccurate")
            and self.best_max_eigenvalue is not None
            and self.best_max_eigenvalue > 0.0
        )


def _cvxpy():
    try:
        import cvxpy
    except ImportError as exc:
        raise AnalysisUnavailable(f"the stability analysis needs cvxpy: {INSTALL_HINT}") from exc
    return cvxpy


def _solve(cp, problem, solver) -> str:
    try:
        with warnings.catch_warnings():  # an inaccurate solution shows in the status, which is reported
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=solver)
    except cp.error.SolverError as exc:
        return f"solver_error ({type(exc).__name__})"
    return str(problem.status)


def _installed(cp, solver: str) -> None:
    if solver not in cp.installed_solvers():
        raise AnalysisUnavailable(
            f"solver {solver} is not installed (installed: {', '.join(cp.installed_solvers()) or 'none'}); {INSTALL_HINT}"
        )


def best_max_eigenvalue(F: np.ndarray, cap: float, solver: str = "CLARABEL") -> tuple[str, float | None]:
    """``(status, t*)`` of ``min t`` s.t. ``I <= P <= cap I``, ``F^T P + P F <= t I`` (always feasible)."""
    cp = _cvxpy()
    _installed(cp, solver)
    F = np.asarray(F, dtype=np.float64)
    scale = float(np.linalg.norm(F, 2)) or 1.0
    Fs = F / scale
    n = F.shape[0]
    eye = np.eye(n)
    P = cp.Variable((n, n), symmetric=True)
    t = cp.Variable()
    lyap = Fs.T @ P + P @ Fs
    problem = cp.Problem(cp.Minimize(t), [P >> eye, P << cap * eye, 0.5 * (lyap + lyap.T) << t * eye])
    status = _solve(cp, problem, solver)
    if t.value is None or status not in ("optimal", "optimal_inaccurate"):
        return status, None
    return status, float(t.value) * scale


def solve_lmi(F: np.ndarray, margin: float, p_floor: float, solver: str = "CLARABEL", cap: float = 100.0) -> LmiSolution:
    """Solve ``P >= p_floor I, F^T P + P F <= -margin I`` minimising ``trace(P)`` (Eq. 32);
    when that finds no verified P, also :func:`best_max_eigenvalue` with ``cap``."""
    cp = _cvxpy()
    _installed(cp, solver)
    F = np.asarray(F, dtype=np.float64)
    n = F.shape[0]
    eye = np.eye(n)
    P = cp.Variable((n, n), symmetric=True)
    lyap = F.T @ P + P @ F
    constraints = [P >> p_floor * eye, 0.5 * (lyap + lyap.T) << -margin * eye]
    status = _solve(cp, cp.Problem(cp.Minimize(cp.trace(P)), constraints), solver)
    Pv = p_eig = lmi_max = None
    verified = False
    if P.value is not None and status in ("optimal", "optimal_inaccurate"):
        Pv = 0.5 * (P.value + P.value.T)
        p_eig = np.linalg.eigvalsh(Pv)
        lmi_max = float(np.max(np.linalg.eigvalsh(F.T @ Pv + Pv @ F)))
        verified = bool(p_eig[0] >= 0.5 * p_floor and lmi_max <= -0.5 * margin)
    if verified:
        return LmiSolution(status, solver, Pv, p_eig, lmi_max, True)
    best_status, t_best = best_max_eigenvalue(F, cap, solver)
    return LmiSolution(status, solver, Pv, p_eig, lmi_max, False, best_status, t_best, cap)
