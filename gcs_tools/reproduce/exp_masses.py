"""Fig. 15: extra masses of 40, 60, 80 and 100 g at 0.33 m on two arms, SMC vs FLC.

Scenario ``extra-mass`` (attitude hold, masses on arms 1 and 2, shocks at 5 and 12 s) with
the mass overridden. A run whose true roll or pitch leaves +-45 deg has diverged
(:func:`~gcs_tools.reproduce.metrics.divergence_time`); it is reported with the time, and
its mean errors and chattering are computed up to that time only (not at all when it
diverges within the first second). Chattering, as Fig. 15 shows it (the controllers' response):
RMS of the roll and pitch errors above 5 Hz (:func:`~gcs_tools.reproduce.metrics.tilt_chattering_deg`),
which the verdict reads; next to it the motor voltage commands'.
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.reproduce import figures, paper_data
from gcs_tools.reproduce.experiment import NOT_REPRODUCED, PARTLY, REPRODUCED, Context, Section, Verdict, fmt, table
from gcs_tools.reproduce.metrics import DIVERGENCE_DEG, divergence_time, hf_rms, tilt_chattering_deg, window_mean_abs

NAME = "masses"
TITLE = "Extra masses on two arms, SMC vs FLC"
PAPER = "Fig. 15"
STRATEGIES = ("smc", "flc")
LOG_HZ = 500.0
CUTOFF_HZ = 5.0
QUICK_S = 6.0
MIN_WINDOW_S = 1.0


def masses(ctx: Context) -> tuple:
    return paper_data.EXTRA_MASSES_KG[-1:] if ctx.quick else paper_data.EXTRA_MASSES_KG


def jobs(ctx: Context) -> list:
    d = paper_data.EXTRA_MASS_DISTANCE_M
    out = []
    for m in masses(ctx):
        extra = [{"arm": 1, "mass": m, "distance": d}, {"arm": 2, "mass": m, "distance": d}]
        for s in STRATEGIES:
            out.append(ctx.job("extra-mass", s, duration=QUICK_S if ctx.quick else None,
                              overrides={"disturbance.extra_masses": extra, "sim.log_rate_hz": LOG_HZ},
                              columns=("t", "euler", "euler_des", "euler_true", "v_cmd"),
                              label=f"{NAME}/{s}/{m * 1000:g}g"))
    return out


def _mass(result) -> float:
    return dict(result.job.overrides)["disturbance.extra_masses"][0]["mass"]


def summarise(result) -> dict:
    s = result.series
    t = s["t"]
    t_div = divergence_time(t, s["euler_true"])
    t_stop = float(t[-1]) if t_div is None else t_div
    out = {"diverged_at_s": t_div, "me_phi_deg": math.nan, "me_theta_deg": math.nan, "chattering_deg_rms": math.nan,
           "chattering_v_rms": math.nan}
    if t_stop - t[0] >= MIN_WINDOW_S:
        err = np.degrees(s["euler"] - s["euler_des"])
        out["me_phi_deg"] = window_mean_abs(t, err[:, 0], 0.0, t[0], t_stop)
        out["me_theta_deg"] = window_mean_abs(t, err[:, 1], 0.0, t[0], t_stop)
        sel = t < t_stop
        out["chattering_deg_rms"] = tilt_chattering_deg(t[sel], s["euler"][sel], s["euler_des"][sel], CUTOFF_HZ)
        out["chattering_v_rms"] = hf_rms(t[sel], s["v_cmd"][sel], CUTOFF_HZ)
    return out


def per_mass(results: list) -> tuple[dict, dict]:
    """The runs' figures by mass label ("40g", ...) and strategy (:func:`summarise`), and each
    label's mass in kg (what :func:`analyse` reports and ``rig-gcs identify --claims`` fits)."""
    per, kg = {}, {}
    for r in results:
        m = _mass(r)
        kg[f"{m * 1000:g}g"] = m
        per.setdefault(f"{m * 1000:g}g", {})[r.job.strategy] = summarise(r)
    return per, kg


def analyse(ctx: Context, results: list, live=None) -> Section:
    per, kg = per_mass(results)
    rows = []
    for mass, runs in per.items():
        for s in STRATEGIES:
            x = runs[s]
            state = "held" if x["diverged_at_s"] is None else f"diverged at {fmt(x['diverged_at_s'], 2)} s"
            rows.append([mass, s.upper(), state, fmt(x["me_phi_deg"], 3), fmt(x["me_theta_deg"], 3),
                         fmt(x["chattering_deg_rms"], 3), fmt(x["chattering_v_rms"], 3)])
    duration = results[0].series["t"][-1]
    body = "\n".join([
        f"Two equal masses at {paper_data.EXTRA_MASS_DISTANCE_M:g} m on arms 1 and 2, attitude hold at zero, shocks "
        f"on arms 3 and 4 at 5 and 12 s, {fmt(duration, 0)} s. Diverged: true roll or pitch beyond "
        f"{DIVERGENCE_DEG:g} deg; mean errors and chattering (RMS above {CUTOFF_HZ:g} Hz of the roll and pitch "
        "errors, what Fig. 15 plots and the verdict reads, and of the motor commands) up to that time.",
        "",
        table(["mass", "strategy", "outcome", "ME phi (deg)", "ME theta (deg)", "chattering (deg rms)",
               "motor commands (V rms)"], rows),
        "",
        "Paper (Fig. 15, 100 g shown): the masses cause chattering, especially with SMC; FLC responds more smoothly "
        "but more slowly; SMC's performance decreases.",
    ])
    verdicts = [_smoother_verdict(per), _smc_holds_verdict(per, kg, results[0].job.config())]
    return Section(NAME, TITLE, PAPER, body, [_figure(ctx, results)], per, verdicts)


def _smoother_verdict(per) -> Verdict:
    ok = []
    for runs in per.values():
        smc, flc = runs["smc"], runs["flc"]
        flc_ok = flc["diverged_at_s"] is None
        smoother = smc["diverged_at_s"] is not None or flc["chattering_deg_rms"] < smc["chattering_deg_rms"]
        ok.append(flc_ok and smoother)
    n_div = sum(r["smc"]["diverged_at_s"] is not None for r in per.values())
    ev = (f"FLC held the attitude with every mass ({', '.join(per)}) and was smoother in {sum(ok)}/{len(ok)}; "
          f"SMC diverged with {n_div}/{len(per)} of the masses")
    status = REPRODUCED if all(ok) else (PARTLY if any(ok) else NOT_REPRODUCED)
    return Verdict("flc_smoother_extra_mass", status, ev)


def _smc_holds_verdict(per, kg, cfg) -> Verdict:
    div = {m: r["smc"]["diverged_at_s"] for m, r in per.items()}
    held = [m for m, t in div.items() if t is None]
    status = REPRODUCED if len(held) == len(div) else (PARTLY if held else NOT_REPRODUCED)
    lost = ", ".join(f"{m} at {fmt(t, 2)} s" for m, t in div.items() if t is not None)
    if not lost:
        return Verdict("smc_holds_extra_mass", status, "SMC held every mass")
    lightest = min(kg[m] for m, t in div.items() if t is not None)
    torque = lightest * cfg["airframe.gravity"] * paper_data.EXTRA_MASS_DISTANCE_M
    authority = cfg["smc.k"][0] * cfg["airframe.ixx"]
    return Verdict("smc_holds_extra_mass", status,
                   f"SMC diverged with {lost}; the gravity torque of {lightest * 1000:g} g at "
                   f"{paper_data.EXTRA_MASS_DISTANCE_M:g} m ({fmt(torque, 3)} N m) exceeds the switching term's "
                   f"K Ixx = {fmt(authority, 3)} N m with the paper's K read in SI")


def _figure(ctx: Context, results) -> str:
    plt = figures.pyplot()
    heaviest = max(_mass(r) for r in results)
    runs = [r for r in results if _mass(r) == heaviest]
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for ax, r in zip(axes, runs):
        s = r.series
        for i, name in enumerate(("phi", "theta", "psi")):
            ax.plot(s["t"], np.degrees(s["euler_true"][:, i]), label=name)
        t_div = divergence_time(s["t"], s["euler_true"])
        if t_div is not None:
            ax.axvline(t_div, color="black", ls="--", lw=0.8, label=f"diverged ({t_div:.2f} s)")
        ax.set_title(f"({'ab'[STRATEGIES.index(r.job.strategy)]}) {r.job.strategy.upper()}, "
                     f"{heaviest * 1000:g} g on arms 1 and 2")
        ax.set_ylabel("angle (deg)")
        ax.legend(loc="upper right")
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Fig. 15 (emulated): extra masses on two arms (true attitude)")
    fig.tight_layout()
    return figures.save(fig, ctx.out_dir, "fig15_extra_mass.png")
