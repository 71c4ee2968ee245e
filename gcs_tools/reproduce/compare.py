"""Your controller next to the paper's four, experiment by experiment: runs, metrics, the verdict rule.

``rig-gcs reproduce --controller package.module:Name`` flies each controller plug-in
(docs/how-to/your-controller.md) and the paper's four controllers (SMC, FLC, SMC-FLC, PID) on the
experiments of the reproduction that a controller can fly (:data:`EXPERIMENTS`), with the same
scenarios, seeds and plants, and compares them metric by metric:

* :func:`jobs` - every controller's headless runs of one (plant, seed);
* :func:`metrics` - each experiment's metrics per controller from those runs (lower is better
  unless :class:`Metric` says otherwise; ``inf`` where the run failed: diverged, never settled,
  never reached the last waypoint, or the plug-in raised, whose error is kept under ``raised``);
* :func:`verdict` - better / worse / same, over the seeds (the rule is :data:`RULE`).

The report (:mod:`gcs_tools.reproduce.compare_report`) and the figures
(:mod:`gcs_tools.reproduce.compare_figures`) are made of these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_tools.reproduce import exp_harmonic, exp_helix, exp_masses, exp_rectangle, exp_shocks, exp_sweep, paper_data
from gcs_tools.reproduce.experiment import Context
from gcs_tools.reproduce.metrics import hf_rms, window_mean_abs
from rig_emulator.sweep import JobFailed, SimJob

#: The paper's four controllers (the built-in strategies), in the order the tables list them.
PAPER_CONTROLLERS = ("smc", "flc", "smc-flc", "pid")
#: The experiments a controller can fly, in report order (names of ``rig-gcs reproduce --only``).
EXPERIMENTS = ("shocks", "harmonic", "sweep", "masses", "helix", "rectangle")
#: "same" unless the means differ by more than this fraction of the larger one (and by more than the metric's atol).
RTOL = 0.05
BETTER, WORSE, SAME = "better", "worse", "same"
RULE = (f"**better** when every seed of yours beats every seed of the paper's controller (the min-max ranges over "
        f"the seeds do not overlap) and the means differ by more than {RTOL:.0%} of the larger and by more than the "
        f"metric's resolution; **worse** the other way round; **same** otherwise (the difference is within the seed "
        f"spread, or too small to matter). A failed run (diverged, not settled, last waypoint not reached) counts as "
        f"worse than any finished one. With one seed there is no spread: only the {RTOL:.0%} and the resolution "
        f"decide; ask for --seeds 3 or more.")


@dataclass(frozen=True)
class Metric:
    """One column of a comparison table."""

    key: str
    label: str  # with its unit
    atol: float  # differences below this are "same" whatever the seeds say (the metric's resolution)
    digits: int = 4
    higher_is_better: bool = False


METRICS = {
    "shocks": (Metric("median_settling_s", "median settling (s)", 0.004, 3),
               Metric("mean_abs_peak_deg", "mean peak (deg)", 0.005, 3),
               Metric("mean_overshoot_pct", "mean overshoot (%)", 0.5, 1),
               Metric("chattering_deg_rms", "chattering (deg rms > 5 Hz)", 0.001, 4)),
    "harmonic": (Metric("phi_deg", "ME phi (deg)", 0.001), Metric("theta_deg", "ME theta (deg)", 0.001),
                 Metric("psi_deg", "ME psi (deg)", 0.001)),
    "sweep": (Metric("phi_deg", "ME phi, average over omega (deg)", 0.001),
              Metric("theta_deg", "ME theta, average over omega (deg)", 0.001)),
    "masses": (Metric("held", "masses held", 0.5, 0, True),
               Metric("phi_deg", "ME phi, heaviest (deg)", 0.001),
               Metric("theta_deg", "ME theta, heaviest (deg)", 0.001),
               Metric("chattering_deg_rms", "chattering, heaviest (deg rms > 5 Hz)", 0.001)),
    "helix": (Metric("phi_deg", "ME phi (deg)", 0.001), Metric("theta_deg", "ME theta (deg)", 0.001),
              Metric("psi_deg", "ME psi (deg)", 0.001), Metric("x_m", "ME X (m)", 0.0005),
              Metric("y_m", "ME Y (m)", 0.0005), Metric("z_m", "ME Z (m)", 0.0005),
              Metric("thrust_n_rms", "thrust (N rms > 5 Hz)", 0.0005)),
    "rectangle": (Metric("reached", "waypoints reached", 0.5, 0, True),
                  Metric("last_s", "last waypoint at (s)", 0.004, 2),
                  Metric("x_m", "ME X (m)", 0.0005), Metric("y_m", "ME Y (m)", 0.0005)),
}
TITLES = {
    "shocks": ("Hover with shocks on the arms", "Fig. 12"),
    "harmonic": ("Harmonic roll and pitch references at 0.4 rad/s", "Eq. 44, Fig. 13"),
    "sweep": ("Frequency sweep of the harmonic reference", "Fig. 14, Table 4"),
    "masses": ("Extra masses on two arms", "Fig. 15"),
    "helix": ("Line-then-helix", "Eq. 46, Fig. 16, Table 6"),
    "rectangle": ("Waypoint rectangle (headless)", "Fig. 19"),
}


def plugins(spec: str) -> list[str]:
    """The plug-ins of ``Context.controller`` (several are separated by commas)."""
    return [p.strip() for p in spec.split(",") if p.strip()]


def names(spec: str) -> dict:
    """plug-in -> its short name in tables: the class name, the whole ``module:Name`` where two share one."""
    ps = plugins(spec)
    short = [p.rsplit(":", 1)[1] for p in ps]
    return {p: (s if short.count(s) == 1 else p) for p, s in zip(ps, short)}


def controllers(spec: str) -> list[str]:
    """Every controller compared: the paper's four, then the plug-ins."""
    return list(PAPER_CONTROLLERS) + plugins(spec)


def label(key: str, spec: str = "") -> str:
    return key.upper() if key in PAPER_CONTROLLERS else names(spec or key).get(key, key)


def experiments(ctx: Context) -> tuple:
    return tuple(e for e in EXPERIMENTS if not ctx.compare or e in ctx.compare)


def _job(ctx: Context, who: str, exp: str, scenario: str, variant: str = "", duration=None, overrides=None,
         columns=None) -> SimJob:
    merged = dict(ctx.overrides)
    merged.update(overrides or {})
    plug = who not in PAPER_CONTROLLERS
    return SimJob(scenario, ctx.strategy if plug else who, seed=ctx.seed, duration=duration, overrides=merged,
                  airframe=ctx.airframe, columns=columns, controller=who if plug else "",
                  label=f"controller/{exp}/{who}" + (f"/{variant}" if variant else ""))


def _harmonic(omega: float) -> dict:
    """Eq. 44's roll and pitch references at ``omega`` (rad/s), yaw held at zero."""
    return {"guidance.omega": omega,
            "guidance.amplitude_deg": [paper_data.HARMONIC_AMPLITUDE_DEG] * 2 + [0.0]}


def jobs(ctx: Context) -> list[SimJob]:
    """Every controller's runs of the compared experiments on ``ctx``'s plant and seed (the experiments'
    own scenarios, durations and logging; ``--quick`` shortens them as it does the reproduction's)."""
    q = ctx.quick
    out = []
    for who in controllers(ctx.controller):
        for exp in experiments(ctx):
            if exp == "shocks":
                out.append(_job(ctx, who, exp, "hover-shocks", duration=exp_shocks.QUICK_S if q else None,
                                overrides={"sim.log_rate_hz": exp_shocks.LOG_HZ},
                                columns=("t", "euler", "euler_des", "v_cmd")))
            elif exp == "harmonic":
                out.append(_job(ctx, who, exp, "harmonic", duration=exp_harmonic.QUICK_S if q else None,
                                overrides=_harmonic(paper_data.HARMONIC_OMEGA),
                                columns=("t", "euler", "euler_des", "pos", "pos_des")))
            elif exp == "sweep":
                for w in exp_sweep.omegas(ctx):
                    out.append(_job(ctx, who, exp, "harmonic", f"{w:g}",
                                    duration=exp_sweep.QUICK_S if q else exp_sweep.duration_for(w),
                                    overrides=_harmonic(w), columns=("t", "euler", "euler_des", "pos", "pos_des")))
            elif exp == "masses":
                d = paper_data.EXTRA_MASS_DISTANCE_M
                for m in exp_masses.masses(ctx):
                    extra = [{"arm": 1, "mass": m, "distance": d}, {"arm": 2, "mass": m, "distance": d}]
                    out.append(_job(ctx, who, exp, "extra-mass", f"{m * 1000:g}g",
                                    duration=exp_masses.QUICK_S if q else None,
                                    overrides={"disturbance.extra_masses": extra, "sim.log_rate_hz": exp_masses.LOG_HZ},
                                    columns=("t", "euler", "euler_des", "euler_true", "v_cmd")))
            elif exp == "helix":
                out.append(_job(ctx, who, exp, "helix", duration=exp_helix.QUICK_S if q else None,
                                overrides={"sim.log_rate_hz": exp_helix.LOG_HZ},
                                columns=("t", "pos", "pos_des", "euler", "euler_des", "thrust")))
            elif exp == "rectangle":
                out.append(_job(ctx, who, exp, "rectangle", duration=exp_rectangle.duration(ctx),
                                columns=("t", "pos", "pos_des")))
    return out


def split(results: list) -> dict:
    """Results by experiment and controller: {exp: {controller: [JobResult, ...]}}, in job order."""
    out: dict = {}
    for r in results:
        _, exp, who = r.job.label.split("/")[:3]
        out.setdefault(exp, {}).setdefault(who, []).append(r)
    return out


def _inf_if_nan(x) -> float:
    x = float(x)
    return math.inf if math.isnan(x) else x


def _shocks(rs) -> dict:
    x = exp_shocks.summarise(rs[0])
    return {"median_settling_s": _inf_if_nan(x["median_settling_s"]), "mean_abs_peak_deg": x["mean_abs_peak_deg"],
            "mean_overshoot_pct": x["mean_overshoot_pct"], "chattering_deg_rms": x["chattering_deg_rms"]}


def _harm(rs) -> dict:
    me = rs[0].mean_errors()
    return {k: me[k] for k in ("phi_deg", "theta_deg", "psi_deg")}


def _sweep(rs) -> dict:
    me = [r.mean_errors() for r in rs]
    out = {k: float(np.mean([m[k] for m in me])) for k in ("phi_deg", "theta_deg")}
    out["per_omega"] = {r.job.label.rsplit("/", 1)[1]: {k: m[k] for k in ("phi_deg", "theta_deg")}
                        for r, m in zip(rs, me)}
    return out


def _masses(rs) -> dict:
    per = [exp_masses.summarise(r) for r in rs]
    heaviest = per[-1]  # masses() is ascending
    failed = heaviest["diverged_at_s"] is not None
    return {"held": sum(x["diverged_at_s"] is None for x in per),
            "phi_deg": math.inf if failed else heaviest["me_phi_deg"],
            "theta_deg": math.inf if failed else heaviest["me_theta_deg"],
            "chattering_deg_rms": math.inf if failed else heaviest["chattering_deg_rms"],
            "diverged_at_s": [x["diverged_at_s"] for x in per]}


def _helix(rs) -> dict:
    r = rs[0]
    out = dict(r.mean_errors())
    out["thrust_n_rms"] = hf_rms(r.series["t"], r.series["thrust"], exp_helix.CUTOFF_HZ)
    return out


def _rectangle(rs) -> dict:
    r = rs[0]
    s = r.series
    t = s["t"]
    reached = r.reached_t
    done = bool(np.all(np.isfinite(reached)))
    end = float(np.nanmax(reached)) if done else float(t[-1])
    me = {k: window_mean_abs(t, s["pos"][:, i], s["pos_des"][:, i], t[0], end) for i, k in enumerate(("x_m", "y_m"))}
    return {"reached": int(np.isfinite(reached).sum()), "last_s": end if done else math.inf, **me}


_SUMMARY = {"shocks": _shocks, "harmonic": _harm, "sweep": _sweep, "masses": _masses, "helix": _helix,
            "rectangle": _rectangle}


def failed_metrics(exp: str, failures: list) -> dict:
    """An experiment's metrics for a controller whose run(s) raised: every metric a failed run (``inf``),
    and ``raised``, each error with the run it stopped."""
    out = {m.key: math.inf for m in METRICS[exp]}
    parts = [f.job.label.split("/") for f in failures]  # controller/EXP/WHO[/VARIANT]
    out["raised"] = ["/".join([p[1], *p[3:]]) + f": {f.message}" for p, f in zip(parts, failures)]
    return out


def metrics(results: list) -> dict:
    """{experiment: {controller: {metric: value}}} of one (plant, seed)'s runs; a :class:`JobFailed`
    among them (``run_jobs(keep_failed=True)``) fails its controller's whole experiment."""
    out: dict = {}
    for exp, by in split(results).items():
        for who, rs in by.items():
            bad = [r for r in rs if isinstance(r, JobFailed)]
            out.setdefault(exp, {})[who] = failed_metrics(exp, bad) if bad else _SUMMARY[exp](rs)
    return out


# --- over the seeds -------------------------------------------------------------------------------------------


def spread(values) -> dict:
    """mean, std (population), min, max and count of one metric over the seeds; a failed seed (inf) makes the
    mean and max inf and is counted in ``failed``."""
    v = np.asarray([float(x) for x in values], dtype=float)
    fin = v[np.isfinite(v)]
    return {"mean": float(np.mean(v)) if fin.size == v.size else (math.inf if v.size else math.nan),
            "std": float(np.std(fin)) if fin.size == v.size and v.size else math.nan,
            "min": float(np.min(v)) if v.size else math.nan, "max": float(np.max(v)) if v.size else math.nan,
            "n": int(v.size), "failed": int(np.sum(np.isinf(v)))}


def verdict(yours, theirs, atol: float, higher_is_better: bool = False, rtol: float = RTOL) -> str:
    """Yours against theirs on one metric, each a list of per-seed values (inf: a failed run): :data:`RULE`."""
    a = np.asarray([float(x) for x in yours], dtype=float)
    b = np.asarray([float(x) for x in theirs], dtype=float)
    if higher_is_better:
        a, b = -a, -b
    if a.size == 0 or b.size == 0 or np.isnan(a).any() or np.isnan(b).any():
        return SAME
    ma, mb = float(np.mean(a)), float(np.mean(b))
    if math.isinf(ma) or math.isinf(mb):  # a failed seed: compare how many failed, then the finished
        fa, fb = int(np.sum(np.isinf(a))), int(np.sum(np.isinf(b)))
        if fa != fb:
            return BETTER if fa < fb else WORSE
        return verdict(a[np.isfinite(a)], b[np.isfinite(b)], atol, False, rtol) if fa < a.size else SAME
    if abs(ma - mb) <= max(atol, rtol * max(abs(ma), abs(mb))):
        return SAME
    if np.max(a) < np.min(b):
        return BETTER
    if np.min(a) > np.max(b):
        return WORSE
    return SAME
