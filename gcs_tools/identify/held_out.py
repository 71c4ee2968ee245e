"""The paper fit judged on numbers it did not see (``rig-gcs identify --paper --held-out``).

The paper's 18 numbers fall in three groups, one per table or figure: Table 4 (4 numbers, the
harmonic sweep), Table 6 (12, the line-then-helix) and Fig. 19 (2, the waypoint rectangle). A
split fits the chosen parameters to some groups and predicts the others with the fitted values:

* ``logo`` (leave one group out): fit on two groups, predict the third; every number is held
  out exactly once, so the held-out figures pool to one prediction of each of the 18;
* ``single``: fit on one group alone, predict the two others.

Every split's fit is :func:`gcs_tools.identify.fit.identify` on a
:class:`~gcs_tools.identify.paper.PaperProblem` restricted to its groups (``targets``), with the
same parameters, bounds, priors and settings. Each evaluated point runs every group's experiments
whatever the split fits, so the held-out numbers come with it, and the splits share their
evaluations (:class:`SharedRecord`: a point one split simulated costs the next nothing).

So that a parameter a split cannot see does not keep the value the whole-paper fit gave it,
every parameter without an explicit start starts from the middle of its bounds (and ``starts``
scrambled Halton points of the bounds, the same for every split). The shipped preset's own
figures (no refit) come first, and optionally a fit on all three groups (``with_all``): its
figures are in-sample only.

The result is a JSON-able document (:func:`run`) and its markdown (:func:`markdown`), which
``rig-gcs reproduce`` includes in its report.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from gcs_tools.identify.paper import FACTOR_2, PaperProblem, load_data, log_residual
from gcs_tools.identify.record import Evaluation, digest

#: the paper's tables and figures, as patterns of the metric names
GROUPS = {"table4": "table4.*", "table6": "table6.*", "fig19": "fig19.*"}
GROUP_TITLES = {"table4": "Table 4", "table6": "Table 6", "fig19": "Fig. 19"}
MODES = ("logo", "single")


def splits(mode: str) -> list[tuple[tuple, tuple]]:
    """(groups fitted, groups predicted) of each split of ``mode``."""
    names = tuple(GROUPS)
    if mode == "logo":
        return [(tuple(g for g in names if g != held), (held,)) for held in names]
    if mode == "single":
        return [((fit,), tuple(g for g in names if g != fit)) for fit in names]
    raise ValueError(f"held-out splits {mode!r}: one of {', '.join(MODES)}")


def group_of(metric: str) -> str:
    return metric.split(".", 1)[0]


class SharedRecord:
    """Evaluated points' metrics, shared by the splits' fits (in memory).

    :meth:`view` gives the record interface :func:`gcs_tools.identify.fit.identify` uses, with
    the residuals of the view's own problem computed from the shared metrics."""

    def __init__(self):
        self.metrics: dict = {}  # digest of the point -> metrics

    def view(self, problem) -> "_View":
        return _View(self, problem)


class _View:
    other_context = 0
    skipped = 0

    def __init__(self, shared: SharedRecord, problem):
        self.shared, self.problem = shared, problem

    def __len__(self) -> int:
        return 0  # (what the fit calls "found in the record": nothing of a file)

    def get(self, point: dict) -> Evaluation | None:
        m = self.shared.metrics.get(digest(point))
        if m is None:
            return None
        return Evaluation(dict(point), self.problem.residuals(m), m, cached=True)

    def add(self, ev: Evaluation, wall_s=None) -> None:
        self.shared.metrics[digest(ev.point)] = ev.metrics


def mid_starts(params: list) -> list:
    """Every parameter without an explicit start starts from the middle of its bounds."""
    return [p if p.start is not None else replace(p, start=0.5 * (p.lo + p.hi)) for p in params]


def figures(metrics: dict, metric_names: list, paper: dict) -> dict:
    """rms log error, count within a factor 2, and n over ``metric_names``."""
    logs = [log_residual(metrics.get(n, math.nan), paper[n]) for n in metric_names]
    if not logs:
        return {"n": 0, "rms_log_error": None, "within_factor_2": 0}
    return {"n": len(logs), "rms_log_error": float(math.sqrt(np.mean(np.square(logs)))),
            "within_factor_2": int(sum(abs(x) <= FACTOR_2 for x in logs))}


def run(base, params: list, *, mode: str = "logo", seed: int = 0, seeds: int = 1, variant: str = "short",
        starts: int = 2, max_evals: int | None = 6, fd_step: float = 0.08, tol: float = 0.01, workers=None,
        with_all: bool = True, show_progress: bool = False, identify=None, evaluate=None) -> dict:
    """Fit ``params`` on each split of ``mode`` and predict its held-out groups (module docstring).

    ``identify`` and ``evaluate`` default to :func:`gcs_tools.identify.fit.identify` and a sweep
    of the problem's jobs; tests pass cheap stand-ins."""
    if identify is None:
        from gcs_tools.identify.fit import identify
    targets, _ = load_data()
    paper = {t.metric: t.value for t in targets}
    order = [t.metric for t in targets]
    params = mid_starts(params)
    shared = SharedRecord()
    settings = {"mode": mode, "seed": seed, "seeds": seeds, "variant": variant, "starts": starts,
                "max_evals": max_evals, "fd_step": fd_step, "tol": tol,
                "params": [p.describe() for p in params]}

    def problem_for(groups) -> PaperProblem:
        return PaperProblem(base, seed=seed, variant=variant, seeds=seeds,
                            targets=",".join(GROUPS[g] for g in groups))

    full = problem_for(tuple(GROUPS))
    if evaluate is None:
        evaluate = _evaluate_shipped
    shipped_metrics = evaluate(full, workers)
    doc = {"settings": settings, "paper": paper,
           "shipped": {"metrics": {n: shipped_metrics.get(n) for n in order},
                       "all": figures(shipped_metrics, order, paper)},
           "splits": []}
    plan = list(splits(mode))
    if with_all:
        plan.append((tuple(GROUPS), ()))
    for fit_groups, held_groups in plan:
        problem = problem_for(fit_groups)
        result = identify(problem, params, record=shared.view(problem), workers=workers, max_evals=max_evals,
                          starts=starts, design_seed=seed, fd_step=fd_step, tol=tol, show_progress=show_progress)
        fit_names = [n for n in order if group_of(n) in fit_groups]
        held_names = [n for n in order if group_of(n) in held_groups]
        doc["splits"].append({
            "fit_on": list(fit_groups), "predict": list(held_groups),
            "values": {p.name: float(v) for p, v in zip(params, result.values)},
            "sigma": {p.name: (float(s) if math.isfinite(s) else None) for p, s in zip(params, result.sigma)},
            "evaluations": result.evaluations, "status": result.status,
            "metrics": {n: result.metrics.get(n) for n in order},
            "in_sample": figures(result.metrics, fit_names, paper),
            "held_out": figures(result.metrics, held_names, paper)})
    doc["pooled_held_out"] = pooled(doc)
    doc["evaluated_points"] = len(shared.metrics)
    return doc


def _evaluate_shipped(problem, workers) -> dict:
    from rig_emulator.sweep import run_jobs

    return problem.metrics(run_jobs(problem.jobs([], []), workers=workers))


def pooled(doc: dict) -> dict:
    """Every split's held-out predictions together: rms log error and within a factor 2."""
    paper = doc["paper"]
    logs = []
    for s in doc["splits"]:
        for n, v in s["metrics"].items():
            if group_of(n) in s["predict"]:
                logs.append(log_residual(math.nan if v is None else v, paper[n]))
    if not logs:
        return {"n": 0, "rms_log_error": None, "within_factor_2": 0}
    return {"n": len(logs), "rms_log_error": float(math.sqrt(np.mean(np.square(logs)))),
            "within_factor_2": int(sum(abs(x) <= FACTOR_2 for x in logs))}


def _fig(f: dict) -> str:
    if not f or not f.get("n"):
        return "-"
    return f"{f['rms_log_error']:.3f} ({f['within_factor_2']} of {f['n']})"


def _groups_text(groups) -> str:
    return " + ".join(GROUP_TITLES[g] for g in groups) if groups else "-"


def _value(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def markdown(doc: dict, command: str | None = None) -> str:
    """The held-out table: one row per split, then each number's predictions."""
    s = doc["settings"]
    keys = [p["key"] for p in s["params"]]
    priors = [f"`{p['key']}` {p['prior'][0]:g} +- {p['prior'][1]:g}" for p in s["params"] if p.get("prior")]
    lines = [f"Fitted keys: {', '.join(f'`{k}`' for k in keys)}; settings: splits `{s['mode']}`, paper variant "
             f"`{s['variant']}`, {s['seeds']} seed(s) from {s['seed']}, {s['starts']} Halton start(s), at most "
             f"{s['max_evals']} points a fit before its final Jacobian, every key starting mid-range; "
             + (f"priors: {', '.join(priors)}" if priors else "no priors") + ".", ""]
    if command:
        lines += [f"Command: `{command}`", ""]
    header = ["fit on", "predict", *[f"`{k}`" for k in keys], "in-sample rms log error (within x2)",
              "held-out rms log error (within x2)"]
    rows = [["(the preset as it is, no refit; these settings)", "-", *["-"] * len(keys),
             _fig(doc["shipped"]["all"]), "-"]]
    for sp in doc["splits"]:
        rows.append([_groups_text(sp["fit_on"]), _groups_text(sp["predict"]),
                     *[_value(sp["values"][k]) for k in keys], _fig(sp["in_sample"]), _fig(sp["held_out"])])
    from gcs_tools.reproduce.experiment import table

    lines.append(table(header, rows))
    p = doc["pooled_held_out"]
    lines += ["", f"All held-out predictions together: rms log error {_fig(p)} (a number predicted by several "
                  "splits counts once per split)."]
    # each number: the paper, the shipped preset, and each split that predicts it
    held = [sp for sp in doc["splits"] if sp["predict"]]
    if held:
        lines += ["", "Each number, simulated / paper, held out (h) or fitted (f):", ""]
        hdr = ["number", "paper", "shipped"] + [f"fit on {_groups_text(sp['fit_on'])}" for sp in held]
        rows = []
        targets, _ = load_data()
        order = [t.metric for t in targets if t.metric in doc["paper"]]
        order += [n for n in doc["paper"] if n not in order]
        for n in order:
            pv = doc["paper"][n]
            sh = doc["shipped"]["metrics"].get(n)
            cells = [n, f"{pv:g}", _ratio(sh, pv)]
            for sp in held:
                tag = "h" if group_of(n) in sp["predict"] else "f"
                cells.append(f"{_ratio(sp['metrics'].get(n), pv)} {tag}")
            rows.append(cells)
        lines.append(table(hdr, rows))
    return "\n".join(lines)


def _ratio(v, paper: float) -> str:
    if v is None or not math.isfinite(v) or v <= 0:
        return "-"
    return f"{v / paper:.2f}x"
