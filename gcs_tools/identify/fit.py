"""The fit: scipy's bounded least squares over headless runs, with a record and a progress bar.

Why ``scipy.optimize.least_squares`` (trust-region reflective, ``method="trf"``): both kinds
of target are residual vectors (log ratios of mean errors to the paper's; scaled differences
of time series), the parameters have hard bounds (the configuration's valid ranges, the
user's), and a run is deterministic for a given seed, so the objective has no sampling noise:
a Gauss-Newton method with a finite-difference Jacobian converges in a few tens of evaluations
where a black-box optimiser (CMA-ES, Bayesian optimisation) needs hundreds, and its Jacobian
at the optimum gives the uncertainty. What is not smooth - a switching controller's chattering,
a fuzzy controller's rule boundaries - is averaged over each run's thousands of control
periods; the finite-difference step is therefore large (``fd_step``, 2 % of each parameter's
range for flight logs, 8 % for the paper's numbers, whose runs we measured to move by a
residual norm of 0.1-0.3 for a 2 % step of any parameter; a parameter's own ``step`` when larger, e.g. a delay the rig rounds to
whole physics steps) rather than at machine precision. For a rough objective or several minima,
``starts`` evaluates a scrambled Halton design of the bounds first (in one parallel sweep) and
starts from its best point.

The optimiser moves ``z`` in [0, 1] per parameter (the bounds mapped linearly), so one step
size suits every parameter. Every Jacobian is evaluated as one batch of points (the
parameters' finite differences side by side), so the workers stay busy; each point's jobs
go through :func:`rig_emulator.sweep.run_jobs` (local processes, or a Dask cluster).

Uncertainty: ``cov = s^2 (J^T J)^-1`` with the Jacobian ``J`` at the optimum (prior rows
included) and ``s^2 = sum(r^2) / (m - n)`` the residual variance (m residuals, n
parameters); one sigma is reported per parameter in its own unit. It is a local, linearised
estimate: it assumes independent residuals of equal variance, which time series (whose
neighbouring samples are correlated) and the paper's 18 numbers (whose misfit is model
error, not noise) satisfy only roughly. A parameter whose column of J is zero is reported as
not identifiable from the targets (infinite sigma); one at a bound has a one-sided interval.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from gcs_tools.identify.params import Param, start_values
from gcs_tools.identify.record import Evaluation, Record, digest

DEFAULT_FD_STEP = 0.02  # flight logs: interval means are smooth in the parameters
PAPER_FD_STEP = 0.08  # the paper's mean errors: a 2 % change moves them by chattering's chaos as much as by effect
DEFAULT_TOL = 1e-3
AT_BOUND = 1e-3  # z this close to 0 or 1 counts as at the bound
NO_EFFECT = 1e-12
POLISH_ROUNDS = 3  # Jacobians evaluated after least_squares stops, at most  # a Jacobian column norm below this: the targets do not see the parameter


class BudgetExhausted(Exception):
    """``max_evals`` points were evaluated; the fit stops at its best point so far."""


@dataclass
class FitResult:
    params: list
    values: list  # fitted, physical units
    sigma: list  # one sigma, physical units (inf: not identifiable)
    at_bound: list  # "lo", "hi" or ""
    correlation: np.ndarray | None
    start: list
    cost: float  # 0.5 sum(r^2) with the priors
    residuals: np.ndarray  # targets only
    prior_residuals: np.ndarray
    metrics: dict
    summary: dict
    evaluations: int  # distinct points of this fit (simulated now + from the record)
    simulated: int  # points simulated now
    runs: int  # headless runs simulated now
    status: str
    wall_s: float
    record: str | None = None
    notes: list = field(default_factory=list)


class _Progress:
    """A tqdm bar of headless runs on a terminal; one line per evaluated batch otherwise."""

    def __init__(self, enabled: bool, stream=None):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.bar = None
        if enabled and getattr(self.stream, "isatty", lambda: False)():
            try:
                from tqdm import tqdm
            except ImportError:
                tqdm = None
            if tqdm is not None:
                self.bar = tqdm(total=0, file=self.stream, unit="run", desc="identify", dynamic_ncols=True)

    def add_runs(self, n: int) -> None:
        if self.bar is not None:
            self.bar.total += n
            self.bar.refresh()

    def run_done(self) -> None:
        if self.bar is not None:
            self.bar.update(1)

    def batch_done(self, text: str) -> None:
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.set_postfix_str(text)
        else:
            print(f"identify: {text}", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


class Evaluator:
    """Parameter points -> :class:`Evaluation` (from the record, else simulated as one sweep)."""

    def __init__(self, problem, params: list[Param], record: Record, *, workers=None, scheduler=None,
                 max_evals: int | None = None, progress: _Progress | None = None):
        self.problem, self.params, self.record = problem, params, record
        self.workers, self.scheduler, self.max_evals = workers, scheduler, max_evals
        self.progress = progress or _Progress(False)
        self.seen: dict = {}  # point key -> Evaluation (this fit's points)
        self.simulated = 0
        self.runs = 0
        self.best: tuple | None = None  # (cost, z tuple)

    def point(self, values) -> dict:
        return {p.name: float(v) for p, v in zip(self.params, values)}

    def prior_residuals(self, values) -> np.ndarray:
        return np.array([(v - p.prior[0]) / p.prior[1] for p, v in zip(self.params, values) if p.prior is not None],
                        dtype=float)

    def total(self, ev: Evaluation, values) -> np.ndarray:
        return np.concatenate([ev.residuals, self.prior_residuals(values)])

    def evaluate_z(self, zs: list) -> list[Evaluation]:
        return self.evaluate([[p.from_unit(z) for p, z in zip(self.params, zz)] for zz in zs], zs)

    def evaluate(self, points: list, zs=None) -> list[Evaluation]:
        from rig_emulator.sweep import run_jobs

        out: list = [None] * len(points)
        todo: dict = {}  # key -> (index list, values)
        for i, values in enumerate(points):
            pt = self.point(values)
            key = digest(pt)
            if key in self.seen:
                out[i] = self.seen[key]
                continue
            ev = self.record.get(pt)
            if ev is not None:
                self._count(key, ev, values, zs[i] if zs is not None else None)
                out[i] = ev
                continue
            todo.setdefault(key, ([], values))[0].append(i)
        if todo:
            if self.max_evals is not None and len(self.seen) + len(todo) > self.max_evals:
                raise BudgetExhausted(f"--max-evals {self.max_evals} reached")
            jobs, spans = [], []
            for key, (idx, values) in todo.items():
                mine = self.problem.jobs(self.params, values)
                spans.append((key, idx, values, len(jobs), len(jobs) + len(mine)))
                jobs += mine
            self.progress.add_runs(len(jobs))
            t0 = time.perf_counter()
            results = run_jobs(jobs, workers=self.workers, scheduler=self.scheduler,
                               progress=lambda done, total, job: self.progress.run_done())
            wall = (time.perf_counter() - t0) / len(todo)
            self.runs += len(jobs)
            for key, idx, values, a, b in spans:
                residuals, metrics = self.problem.evaluate(results[a:b])
                ev = Evaluation(self.point(values), residuals, metrics)
                self.record.add(ev, wall_s=wall)
                self.simulated += 1
                self._count(key, ev, values, zs[idx[0]] if zs is not None else None)
                for i in idx:
                    out[i] = ev
        best = f"best cost {self.best[0]:.4g}" if self.best else ""
        self.progress.batch_done(f"{len(self.seen)} points ({self.simulated} simulated), {best}")
        return out

    def _count(self, key, ev, values, z) -> None:
        self.seen[key] = ev
        r = self.total(ev, values)
        cost = 0.5 * float(r @ r)
        zz = tuple(p.to_unit(v) for p, v in zip(self.params, values)) if z is None else tuple(float(x) for x in z)
        if self.best is None or cost < self.best[0]:
            self.best = (cost, zz)


def fd_steps(params: list[Param], step: float) -> np.ndarray:
    """Each parameter's finite-difference step in z: ``step``, or its own ``step`` when larger."""
    return np.array([min(0.5, max(step, (p.step or 0.0) / (p.hi - p.lo))) for p in params])


def _fd_points(z: np.ndarray, steps: np.ndarray) -> tuple[list, np.ndarray]:
    pts, hs = [], np.empty(z.size)
    for i in range(z.size):
        step = steps[i]
        h = step if z[i] + step <= 1.0 else -step
        zz = z.copy()
        zz[i] += h
        pts.append(zz)
        hs[i] = h
    return pts, hs


def jacobian(ev: Evaluator, z: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """(residual vector at z, forward-difference Jacobian in z), the n+1 points as one batch."""
    pts, hs = _fd_points(z, fd_steps(ev.params, step))
    evs = ev.evaluate_z([z] + pts)
    vals = [[p.from_unit(x) for p, x in zip(ev.params, zz)] for zz in [z] + pts]
    f0 = ev.total(evs[0], vals[0])
    cols = [(ev.total(e, v) - f0) / h for e, v, h in zip(evs[1:], vals[1:], hs)]
    return f0, np.column_stack(cols)


def halton_design(n_params: int, count: int, seed: int) -> list[np.ndarray]:
    from scipy.stats import qmc

    return list(qmc.Halton(d=n_params, scramble=True, seed=seed).random(count))


def identify(problem, params: list[Param], *, record_path=None, workers=None, scheduler=None,
             max_evals: int | None = None, starts: int = 0, design_seed: int = 0,
             fd_step: float = DEFAULT_FD_STEP, tol: float = DEFAULT_TOL, show_progress: bool = True,
             stream=None, record=None) -> FitResult:
    """Fit ``params`` to ``problem``'s targets (see the module docstring). ``record``: an object with the
    :class:`~gcs_tools.identify.record.Record` interface to use instead of one on ``record_path`` (the
    held-out splits share their evaluations through one, :mod:`gcs_tools.identify.held_out`)."""
    if not params:
        raise ValueError("no parameter to fit")
    if not 0.0 < fd_step < 0.5:
        raise ValueError(f"fd_step {fd_step!r}: must be in (0, 0.5)")
    t0 = time.perf_counter()
    own_client = None
    if isinstance(scheduler, str):  # one connection to the cluster for the whole fit, not one per batch
        try:
            from distributed import Client
        except ImportError:
            raise RuntimeError("running on a Dask cluster needs dask.distributed: pip install 'hilms-sil[cluster]'") \
                from None
        scheduler = own_client = Client(scheduler, timeout="30s")
    try:
        return _identify(problem, params, t0, record_path, workers, scheduler, max_evals, starts, design_seed,
                         fd_step, tol, show_progress, stream, record)
    finally:
        if own_client is not None:
            own_client.close()


def _identify(problem, params, t0, record_path, workers, scheduler, max_evals, starts, design_seed, fd_step, tol,
              show_progress, stream, record=None) -> FitResult:
    from scipy.optimize import least_squares

    context = digest({"problem": problem.context(), "params": [p.describe() for p in params],
                      "emulator": emulator_fingerprint()})
    if record is None:
        record = Record(record_path, context)
    progress = _Progress(show_progress, stream)
    ev = Evaluator(problem, params, record, workers=workers, scheduler=scheduler, max_evals=max_evals,
                   progress=progress)
    notes = []
    if record.other_context:
        notes.append(f"{record.other_context} evaluation(s) in the record belong to another fit or emulator "
                     "build and were not used")
    if record.skipped:
        notes.append(f"{record.skipped} unreadable line(s) of the record were skipped (an interrupted write)")
    if len(record):
        notes.append(f"{len(record)} evaluation(s) of this fit found in the record")
    start = start_values(params, problem.configs()[0])
    z0 = np.array([p.to_unit(v) for p, v in zip(params, start)])
    status = ""
    jac_cache: dict = {}

    def fun(z):
        (e,) = ev.evaluate_z([np.asarray(z)])
        return ev.total(e, [p.from_unit(x) for p, x in zip(params, z)])

    def jac(z, *args):
        f0, j = jacobian(ev, np.asarray(z, dtype=float), fd_step)
        jac_cache[tuple(float(x) for x in z)] = (f0, j)
        return j

    try:
        if starts > 0:
            design = [z0] + halton_design(len(params), starts, design_seed)
            ev.evaluate_z(design)
            z0 = np.array(ev.best[1])
        z0 = np.clip(z0, 0.0, 1.0)
        res = least_squares(fun, z0, jac=jac, bounds=(0.0, 1.0), method="trf", x_scale=1.0,
                            ftol=tol, xtol=tol, gtol=tol)
        z_best = np.asarray(res.x, dtype=float)
        status = res.message
        # least_squares returns its last accepted point; the best one seen is never worse
        f_best = fun(z_best)
        if ev.best is not None and ev.best[0] < 0.5 * float(f_best @ f_best):
            z_best = np.array(ev.best[1])
    except BudgetExhausted as exc:
        status = f"stopped: {exc}; the best point evaluated is reported"
        z_best = np.array(ev.best[1]) if ev.best is not None else z0
    # the Jacobian at the optimum (from the cache when least_squares computed it there); its
    # finite-difference points may hold a better point (least_squares stops on a small step before
    # accepting it, or the objective is rough): then that point and its Jacobian, a few times at most
    ev.max_evals = None
    try:
        for _ in range(POLISH_ROUNDS):
            key = tuple(float(x) for x in z_best)
            f_opt, j = jac_cache[key] if key in jac_cache else jacobian(ev, z_best, fd_step)
            if ev.best is None or ev.best[0] >= 0.5 * float(f_opt @ f_opt):
                break
            z_best = np.array(ev.best[1])
            status += "; a better point found by the final Jacobian is reported"
        else:
            key = tuple(float(x) for x in z_best)
            f_opt, j = jac_cache[key] if key in jac_cache else jacobian(ev, z_best, fd_step)
    finally:
        progress.close()
    values = [p.from_unit(z) for p, z in zip(params, z_best)]
    (e_best,) = ev.evaluate([values])
    sigma, corr = uncertainty(f_opt, j, params)
    at_bound = ["lo" if z <= AT_BOUND else "hi" if z >= 1 - AT_BOUND else "" for z in z_best]
    return FitResult(params=params, values=values, sigma=sigma, at_bound=at_bound, correlation=corr,
                     start=start, cost=0.5 * float(f_opt @ f_opt), residuals=e_best.residuals,
                     prior_residuals=ev.prior_residuals(values), metrics=e_best.metrics,
                     summary=problem.summary(e_best.residuals, e_best.metrics), evaluations=len(ev.seen),
                     simulated=ev.simulated, runs=ev.runs, status=status, wall_s=time.perf_counter() - t0,
                     record=str(record_path) if record_path is not None else None, notes=notes)


def uncertainty(f: np.ndarray, j: np.ndarray, params: list[Param]) -> tuple[list, np.ndarray | None]:
    """One sigma per parameter (physical units) and the correlation matrix, from ``s^2 (J^T J)^-1``."""
    m, n = j.shape
    s2 = float(f @ f) / max(m - n, 1)
    norms = np.linalg.norm(j, axis=0)
    seen = norms > NO_EFFECT
    sigma = [math.inf] * n
    corr = None
    if np.any(seen):
        js = j[:, seen]
        cov = s2 * np.linalg.pinv(js.T @ js)
        d = np.sqrt(np.maximum(np.diag(cov), 0.0))
        k = 0
        for i in range(n):
            if seen[i]:
                sigma[i] = float(d[k]) * (params[i].hi - params[i].lo)
                k += 1
        with np.errstate(invalid="ignore", divide="ignore"):
            c = cov / np.outer(d, d)
        corr = np.full((n, n), np.nan)
        idx = np.flatnonzero(seen)
        corr[np.ix_(idx, idx)] = c
    return sigma, corr


def emulator_fingerprint() -> str:
    """SHA-256 over the emulator's and the targets' source files (a changed model is another fit)."""
    import hashlib
    from importlib import resources

    h = hashlib.sha256()
    for pkg in ("rig_emulator", "protocol", "gcs_tools.reproduce", "gcs_tools.identify"):
        root = resources.files(pkg)
        files = []

        def walk(node, rel=""):
            for child in node.iterdir():
                name = f"{rel}/{child.name}"
                if child.is_dir():
                    if child.name != "__pycache__":
                        walk(child, name)
                elif child.name.endswith((".py", ".toml", ".xml")):
                    files.append((name, child))

        walk(root)
        for name, child in sorted(files, key=lambda x: x[0]):
            h.update(f"{pkg}{name}\0".encode())
            h.update(child.read_bytes())
    return h.hexdigest()
