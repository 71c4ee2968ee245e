"""Fig. 13, Eq. 44: harmonic roll and pitch references, 10 deg at omega = 0.4 rad/s, SMC vs FLC.

Scenario ``harmonic`` (two periods, 31.4 s). Mean errors by Eq. 45 over the run. "Tracks"
(the paper's word, no number) is read here as a mean error below 10 % of the amplitude.
"""

from __future__ import annotations

import numpy as np

from gcs_tools.reproduce import figures, paper_data
from gcs_tools.reproduce.experiment import Context, Section, Verdict, fmt, status_of, table

NAME = "harmonic"
TITLE = "Harmonic roll and pitch tracking at 0.4 rad/s"
PAPER = "Eq. 44, Fig. 13"
STRATEGIES = ("smc", "flc")
QUICK_S = 10.0
TRACK_FRACTION = 0.1  # "tracks": mean error below this fraction of the amplitude


def jobs(ctx: Context) -> list:
    return [ctx.job("harmonic", s, duration=QUICK_S if ctx.quick else None,
                   overrides={"guidance.omega": paper_data.HARMONIC_OMEGA,
                              "guidance.amplitude_deg": [paper_data.HARMONIC_AMPLITUDE_DEG] * 2 + [0.0]},
                   columns=("t", "euler", "euler_des", "pos", "pos_des"), label=f"{NAME}/{s}")
            for s in STRATEGIES]


def analyse(ctx: Context, results: list, live=None) -> Section:
    per = {r.job.strategy: {k: v for k, v in r.mean_errors().items() if k.endswith("_deg")} for r in results}
    limit = TRACK_FRACTION * paper_data.HARMONIC_AMPLITUDE_DEG
    rows = [[s.upper(), fmt(per[s]["phi_deg"], 4), fmt(per[s]["theta_deg"], 4), fmt(per[s]["psi_deg"], 4)]
            for s in STRATEGIES]
    duration = results[0].series["t"][-1]
    body = "\n".join([
        f"phi_des = theta_des = {paper_data.HARMONIC_AMPLITUDE_DEG:g} sin({paper_data.HARMONIC_OMEGA:g} t) deg, "
        f"psi_des = 0, {fmt(duration, 1)} s. Mean errors (Eq. 45) over the run:",
        "",
        table(["strategy", "ME phi (deg)", "ME theta (deg)", "ME psi (deg)"], rows),
        "",
        "Paper (Fig. 13, no numbers): both controllers track the reference.",
    ])
    worst = max(max(per[s]["phi_deg"], per[s]["theta_deg"]) for s in STRATEGIES)
    verdict = Verdict("both_track_harmonic", status_of(worst < limit),
                      f"largest roll/pitch mean error {fmt(worst, 3)} deg (SMC {fmt(per['smc']['phi_deg'], 3)}/"
                      f"{fmt(per['smc']['theta_deg'], 3)}, FLC {fmt(per['flc']['phi_deg'], 3)}/"
                      f"{fmt(per['flc']['theta_deg'], 3)} deg) against the {fmt(limit, 1)} deg "
                      f"({TRACK_FRACTION:.0%} of the amplitude) read as tracking")
    return Section(NAME, TITLE, PAPER, body, [_figure(ctx, results)], per, [verdict])


def _figure(ctx: Context, results) -> str:
    plt = figures.pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for ax, r in zip(axes, results):
        s = r.series
        t = s["t"]
        for i, name in enumerate(("phi", "theta")):
            ax.plot(t, np.degrees(s["euler"][:, i]), label=name)
            ax.plot(t, np.degrees(s["euler_des"][:, i]), "--", color="black", lw=0.8,
                    label="desired" if i == 0 else None)
        ax.set_title(f"{r.job.strategy.upper()}")
        ax.set_ylabel("angle (deg)")
        ax.legend(loc="upper right")
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Fig. 13 (emulated): harmonic roll and pitch, 10 deg at 0.4 rad/s")
    fig.tight_layout()
    return figures.save(fig, ctx.out_dir, "fig13_harmonic.png")
