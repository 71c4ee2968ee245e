"""Fig. 14, Table 4: the harmonic reference of Eq. 44 swept from 0.1 to 2 rad/s, SMC vs FLC.

The paper does not list its frequencies; we use 13 from 0.1 to 2 rad/s. Each run lasts a
whole number of periods and at least 20 s, so every mean error (Eq. 45) averages whole
cycles. Table 4 is the average over the frequencies.
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.reproduce import figures, paper_data
from gcs_tools.reproduce.experiment import (NOT_REPRODUCED, PARTLY, REPRODUCED, Context, Section, Verdict, fmt,
                                            status_of, table, times)
from gcs_tools.reproduce.metrics import improvement_pct

NAME = "sweep"
TITLE = "Frequency sweep of the harmonic reference, SMC vs FLC"
PAPER = "Fig. 14, Table 4"
STRATEGIES = ("smc", "flc")
OMEGAS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0)
QUICK_OMEGAS = (0.4, 2.0)
MIN_S = 20.0
QUICK_S = 6.0
FLAT_RATIO = 2.0  # "almost unchanged": largest / smallest mean error over the frequencies below this


def duration_for(omega: float) -> float:
    """Whole periods of the reference, at least MIN_S seconds."""
    period = 2.0 * math.pi / omega
    return math.ceil(MIN_S / period - 1e-9) * period


def omegas(ctx: Context) -> tuple:
    return QUICK_OMEGAS if ctx.quick else OMEGAS


def jobs(ctx: Context) -> list:
    out = []
    for w in omegas(ctx):
        for s in STRATEGIES:
            out.append(ctx.job("harmonic", s, duration=QUICK_S if ctx.quick else duration_for(w),
                              overrides={"guidance.omega": w,
                                         "guidance.amplitude_deg": [paper_data.HARMONIC_AMPLITUDE_DEG] * 2 + [0.0]},
                              columns=("t", "euler", "euler_des", "pos", "pos_des"), label=f"{NAME}/{s}/{w:g}"))
    return out


def analyse(ctx: Context, results: list, live=None) -> Section:
    ws = omegas(ctx)
    me = {s: {"phi_deg": [], "theta_deg": []} for s in STRATEGIES}
    for r in results:
        errs = r.mean_errors()
        for k in ("phi_deg", "theta_deg"):
            me[r.job.strategy][k].append(errs[k])
    avg = {s: {k: float(np.mean(v)) for k, v in me[s].items()} for s in STRATEGIES}
    impr = {k: improvement_pct(avg["smc"][k], avg["flc"][k]) for k in ("phi_deg", "theta_deg")}
    rows = [[fmt(w, 1), fmt(me["smc"]["phi_deg"][i], 4), fmt(me["smc"]["theta_deg"][i], 4),
             fmt(me["flc"]["phi_deg"][i], 4), fmt(me["flc"]["theta_deg"][i], 4)] for i, w in enumerate(ws)]
    t4 = paper_data.TABLE_4
    body = "\n".join([
        f"phi_des = theta_des = {paper_data.HARMONIC_AMPLITUDE_DEG:g} sin(omega t) deg, omega = "
        f"{', '.join(f'{w:g}' for w in ws)} rad/s; each run "
        + ("6 s (quick)." if ctx.quick else f"a whole number of periods, at least {MIN_S:g} s."),
        "",
        table(["omega (rad/s)", "SMC ME phi (deg)", "SMC ME theta (deg)", "FLC ME phi (deg)", "FLC ME theta (deg)"],
              rows),
        "",
        "Table 4, average over the frequencies (ours next to the paper's):",
        "",
        table(["strategy", "ME phi ours (deg)", "ME phi paper", "ME theta ours (deg)", "ME theta paper"],
              [[s.upper(), fmt(avg[s]["phi_deg"], 4), fmt(t4[s]["phi_deg"], 4), fmt(avg[s]["theta_deg"], 4),
                fmt(t4[s]["theta_deg"], 4)] for s in STRATEGIES]
              + [["FLC improvement", f"{fmt(impr['phi_deg'], 1)} %",
                  f"{fmt(paper_data.TABLE_4_FLC_IMPROVEMENT_PCT['phi_deg'], 1)} %", f"{fmt(impr['theta_deg'], 1)} %",
                  f"{fmt(paper_data.TABLE_4_FLC_IMPROVEMENT_PCT['theta_deg'], 1)} %"]]),
    ])
    numbers = {"omega_rad_s": list(ws), "mean_error_deg": me, "table4_average_deg": avg,
               "flc_improvement_pct": impr}
    verdicts = [_tracks_verdict(avg, impr), _flat_verdict(ws, me), _moderate_verdict(ws, me)]
    return Section(NAME, TITLE, PAPER, body, [_figure(ctx, ws, me, avg)], numbers, verdicts)


def _tracks_verdict(avg, impr) -> Verdict:
    ok = all(avg["flc"][k] < avg["smc"][k] for k in ("phi_deg", "theta_deg"))
    return Verdict("flc_tracks_better", status_of(ok),
                   f"average ME over the sweep: FLC {fmt(avg['flc']['phi_deg'], 4)}/{fmt(avg['flc']['theta_deg'], 4)} "
                   f"deg vs SMC {fmt(avg['smc']['phi_deg'], 4)}/{fmt(avg['smc']['theta_deg'], 4)} deg (roll/pitch): "
                   f"FLC {fmt(impr['phi_deg'], 1)} %/{fmt(impr['theta_deg'], 1)} % better (paper 14 %/25.3 %); "
                   f"our roll averages are {times(avg['flc']['phi_deg'], paper_data.TABLE_4['flc']['phi_deg'])} "
                   f"Table 4's (FLC) and {times(avg['smc']['phi_deg'], paper_data.TABLE_4['smc']['phi_deg'])} it (SMC)")


def _flat_verdict(ws, me) -> Verdict:
    if len(ws) < 2:
        return Verdict("flc_flat_over_frequency", NOT_REPRODUCED, "only one frequency was run")
    ratios = {k: max(v) / min(v) if min(v) > 0 else math.inf for k, v in me["flc"].items()}
    worst = max(ratios.values())
    return Verdict("flc_flat_over_frequency", status_of(worst < FLAT_RATIO),
                   f"FLC mean error grows {fmt(ratios['phi_deg'], 1)}x (roll) and {fmt(ratios['theta_deg'], 1)}x "
                   f"(pitch) from {ws[0]:g} to {ws[-1]:g} rad/s (read as unchanged below {FLAT_RATIO:g}x)")


def _moderate_verdict(ws, me) -> Verdict:
    both = np.mean([me["smc"]["phi_deg"], me["smc"]["theta_deg"]], axis=0)
    k = int(np.argmin(both))
    interior = 0 < k < len(ws) - 1
    status = REPRODUCED if interior else NOT_REPRODUCED
    if len(ws) < 3:
        status = PARTLY if interior else NOT_REPRODUCED
    where = "inside the range" if interior else ("the lowest frequency run" if k == 0 else "the highest frequency run")
    return Verdict("smc_best_at_moderate", status, f"SMC's smallest mean error is at {ws[k]:g} rad/s ({where})")


def _figure(ctx: Context, ws, me, avg) -> str:
    plt = figures.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, key, label in zip(axes, ("phi_deg", "theta_deg"), ("(a) roll", "(b) pitch")):
        for s in STRATEGIES:
            ax.plot(ws, me[s][key], "o-", color=figures.COLORS[s], label=f"{s.upper()} (ours)")
            ax.axhline(avg[s][key], color=figures.COLORS[s], ls=":", lw=0.8)
            ax.axhline(paper_data.TABLE_4[s][key], color=figures.COLORS[s], ls="--", lw=0.8,
                       label=f"{s.upper()} Table 4 average (paper)")
        ax.set_yscale("log")
        ax.set_xlabel("omega (rad/s)")
        ax.set_ylabel("mean error (deg)")
        ax.set_title(f"{label}; dotted: our average")
        ax.legend(loc="lower right")
    fig.suptitle("Fig. 14 (emulated): mean error against the frequency of the harmonic reference")
    fig.tight_layout()
    return figures.save(fig, ctx.out_dir, "fig14_sweep.png")
