"""Your controller next to the paper's: ``rig-gcs reproduce -o DIR --controller package.module:Name``.

Runs a controller plug-in (docs/YOUR_CONTROLLER.md) on the paper's experiments that report
numbers or a tracking claim, beside the built-in strategies the paper flew, same seed and
rig:

* the line-then-helix of Eq. 46 (Table 6): mean errors (Eq. 45) of the plug-in, of FLC and
  SMC-FLC here, and the paper's Table 6 rows;
* the harmonic roll and pitch references of Eq. 44 / Fig. 13: attitude mean errors of the
  plug-in, SMC and FLC (the paper gives no numbers there).

The plug-in keeps the loops it does not replace from ``--strategy`` (default ``smc-flc``, the
paper's proposal). A position-only plug-in does not fly the harmonic run (attitude
references, the position loop is off): that row then shows the kept attitude loop. There is
no verdict: the paper makes no claim about your controller.
"""

from __future__ import annotations

from gcs_tools.reproduce import paper_data
from gcs_tools.reproduce.experiment import Context, Section, fmt, table
from protocol.mean_error import COLUMNS
from rig_emulator.sweep import SimJob

NAME = "controller"
TITLE = "Your controller next to the paper's"
PAPER = "Table 6, Eq. 44"
HELIX = ("flc", "smc-flc")
HARMONIC = ("smc", "flc")
QUICK_S = 20.0
PLUGIN = "plugin"


def jobs(ctx: Context) -> list[SimJob]:
    quick = QUICK_S if ctx.quick else None
    helix_cols = ("t", "pos", "pos_des", "euler", "euler_des")
    out = [SimJob("helix", ctx.strategy, seed=ctx.seed, duration=quick, columns=helix_cols, label=f"{NAME}/helix/{PLUGIN}",
                  controller=ctx.controller)]
    out += [SimJob("helix", s, seed=ctx.seed, duration=quick, columns=helix_cols, label=f"{NAME}/helix/{s}")
            for s in HELIX]
    harmonic = {"guidance.omega": paper_data.HARMONIC_OMEGA,
                "guidance.amplitude_deg": [paper_data.HARMONIC_AMPLITUDE_DEG] * 2 + [0.0]}
    out.append(SimJob("harmonic", ctx.strategy, seed=ctx.seed, duration=quick, overrides=harmonic, columns=helix_cols,
                      label=f"{NAME}/harmonic/{PLUGIN}", controller=ctx.controller))
    out += [SimJob("harmonic", s, seed=ctx.seed, duration=quick, overrides=harmonic, columns=helix_cols,
                   label=f"{NAME}/harmonic/{s}") for s in HARMONIC]
    return out


def analyse(ctx: Context, results: list, live=None) -> Section:
    me = {r.job.label.split("/", 1)[1]: r.mean_errors() for r in results}
    who = f"`{ctx.controller}`"
    helix_rows = [[f"{who} (ours)"] + [fmt(me[f'helix/{PLUGIN}'][c], 4) for c in COLUMNS]]
    for s in HELIX:
        helix_rows.append([f"{s.upper()} (ours)"] + [fmt(me[f"helix/{s}"][c], 4) for c in COLUMNS])
    for s in HELIX:
        helix_rows.append([f"{s.upper()} (paper)"] + [fmt(paper_data.TABLE_6[s][c], 4) for c in COLUMNS])
    att = ("phi_deg", "theta_deg", "psi_deg")
    harm_rows = [[f"{who} (ours)"] + [fmt(me[f"harmonic/{PLUGIN}"][c], 4) for c in att]]
    harm_rows += [[f"{s.upper()} (ours)"] + [fmt(me[f"harmonic/{s}"][c], 4) for c in att] for s in HARMONIC]
    duration = results[0].series["t"][-1]
    body = "\n".join([
        f"Controller plug-in {who}; the loops it does not replace are those of strategy `{ctx.strategy}`. Same seed "
        f"({ctx.seed}) and rig for every row.",
        "",
        f"Line-then-helix (Eq. 46), {fmt(duration, 0)} s, mean errors (Eq. 45), Table 6:",
        "",
        table(["", "ME phi (deg)", "ME theta (deg)", "ME psi (deg)", "ME X (m)", "ME Y (m)", "ME Z (m)"], helix_rows),
        "",
        f"Harmonic roll and pitch references (Eq. 44, {paper_data.HARMONIC_AMPLITUDE_DEG:g} deg at "
        f"{paper_data.HARMONIC_OMEGA:g} rad/s; Fig. 13 has no numbers), mean errors:",
        "",
        table(["", "ME phi (deg)", "ME theta (deg)", "ME psi (deg)"], harm_rows),
    ])
    numbers = {"controller": ctx.controller, "strategy": ctx.strategy, "mean_errors": me}
    return Section(NAME, TITLE, PAPER, body, [], numbers, [])
