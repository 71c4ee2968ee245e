"""The comparison's figures: the reproduction's plots with every compared controller drawn in.

One PNG per experiment and (plant, seed), written by :func:`draw` from that seed's runs
(:func:`gcs_tools.reproduce.compare.split`); bit-identical for the same runs
(:mod:`gcs_tools.reproduce.figures`).
"""

from __future__ import annotations

import numpy as np

from gcs_tools.reproduce import compare, figures, paper_data
from gcs_tools.reproduce.metrics import divergence_time

PLUGIN_COLORS = ("tab:purple", "tab:pink", "tab:cyan", "tab:olive", "tab:gray")
FILES = {"shocks": "fig12_shocks_compare.png", "harmonic": "fig13_harmonic_compare.png",
         "sweep": "fig14_sweep_compare.png", "masses": "fig15_extra_mass_compare.png",
         "helix": "fig16_helix_compare.png", "rectangle": "fig19_rectangle_compare.png"}


def color(who: str, spec: str) -> str:
    if who in compare.PAPER_CONTROLLERS:
        return {"pid": "tab:brown"}.get(who, figures.COLORS.get(who, "tab:gray"))
    return PLUGIN_COLORS[compare.plugins(spec).index(who) % len(PLUGIN_COLORS)]


def _style(who: str, spec: str) -> dict:
    mine = who not in compare.PAPER_CONTROLLERS
    return {"color": color(who, spec), "lw": 1.6 if mine else 0.9, "zorder": 3 if mine else 2,
            "label": compare.label(who, spec) + (" (yours)" if mine else "")}


def _limit(peaks: dict) -> float | None:
    """A y-limit that keeps the controllers that stayed near the reference readable when one ran away
    (None: every curve fits): three times the median peak, at least every plug-in's peak."""
    values = np.asarray(list(peaks.values()), dtype=float)
    lim = max(3.0 * float(np.median(values)),
              max((v for w, v in peaks.items() if w not in compare.PAPER_CONTROLLERS), default=0.0))
    return lim * 1.05 if np.any(values > lim * 1.05) and lim > 0 else None


def _off_scale(ax, lines: dict, peaks: dict, lim) -> None:
    """Clip the axis at +-lim and say in the legend which controllers leave it."""
    if lim is None:
        return
    ax.set_ylim(-lim, lim)
    for who, line in lines.items():
        if peaks[who] > lim:
            line.set_label(line.get_label() + " (off scale)")


def _shocks(ax_rows, by, spec):
    for ax, (who, rs) in zip(ax_rows, by.items()):
        s = rs[0].series
        err = np.degrees(s["euler"] - s["euler_des"])
        for i, name in enumerate(("phi", "theta")):  # the axes the shocks disturb (yaw: magnetometer noise)
            ax.plot(s["t"], err[:, i], lw=0.7, label=name)
        ax.set_title(_style(who, spec)["label"], fontsize=9, loc="left")
        ax.set_ylabel("error (deg)")
        ax.legend(loc="upper right", ncol=3)


def draw(ctx, results: list) -> list[str]:
    """The comparison figures of one (plant, seed) into ``ctx.out_dir``; their file names."""
    plt = figures.pyplot()
    spec = ctx.controller
    out = []
    for exp, by in compare.split(results).items():
        where = f"{ctx.airframe}, seed {ctx.seed}"
        if exp == "shocks":
            fig, axes = plt.subplots(len(by), 1, figsize=(10, 1.7 * len(by) + 1), sharex=True, sharey=True)
            _shocks(np.atleast_1d(axes), by, spec)
            np.atleast_1d(axes)[-1].set_xlabel("t (s)")
            fig.suptitle(f"Fig. 12 compared: roll and pitch error under the shocks ({where})")
        elif exp == "harmonic":
            fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
            for who, rs in by.items():
                s = rs[0].series
                for i, ax in enumerate(axes):
                    ax.plot(s["t"], np.degrees(s["euler"][:, i]), **_style(who, spec))
            s = next(iter(by.values()))[0].series
            for i, (ax, name) in enumerate(zip(axes, ("phi", "theta"))):
                ax.plot(s["t"], np.degrees(s["euler_des"][:, i]), "--", color="black", lw=0.8, label="desired")
                ax.set_ylabel(f"{name} (deg)")
                ax.legend(loc="upper right", ncol=3)
            axes[-1].set_xlabel("t (s)")
            fig.suptitle(f"Fig. 13 compared: harmonic roll and pitch, {paper_data.HARMONIC_AMPLITUDE_DEG:g} deg at "
                         f"{paper_data.HARMONIC_OMEGA:g} rad/s ({where})")
        elif exp == "sweep":
            fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
            for ax, key, title in zip(axes, ("phi_deg", "theta_deg"), ("(a) roll", "(b) pitch")):
                for who, rs in by.items():
                    ws = [float(r.job.label.rsplit("/", 1)[1]) for r in rs]
                    me = [r.mean_errors()[key] for r in rs]
                    ax.plot(ws, me, "o-", ms=3, **_style(who, spec))
                ax.set_yscale("log")
                ax.set_xlabel("omega (rad/s)")
                ax.set_ylabel("mean error (deg)")
                ax.set_title(title)
                ax.legend(loc="best")
            fig.suptitle(f"Fig. 14 compared: mean error against the frequency of the reference ({where})")
        elif exp == "masses":
            fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
            heaviest, diverged = None, False
            for who, rs in by.items():
                r = rs[-1]
                heaviest = r.job.label.rsplit("/", 1)[1]
                s = r.series
                for i, ax in enumerate(axes):
                    ax.plot(s["t"], np.degrees(s["euler_true"][:, i]), **_style(who, spec))
                t_div = divergence_time(s["t"], s["euler_true"])
                if t_div is not None:
                    diverged = True
                    for ax in axes:
                        ax.axvline(t_div, color=color(who, spec), ls=":", lw=0.8)
            for ax, name in zip(axes, ("phi", "theta")):
                ax.set_ylabel(f"true {name} (deg)")
                if diverged:  # a tipped rig: show up to a little past the 45 deg that count as diverged
                    ax.set_ylim(-50, 50)
                ax.legend(loc="upper right", ncol=3)
            axes[-1].set_xlabel("t (s)")
            fig.suptitle(f"Fig. 15 compared: {heaviest} on arms 1 and 2, true attitude (dotted: diverged) ({where})")
        elif exp == "helix":
            fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
            for i, ax in enumerate(axes):
                lines, peaks = {}, {}
                for who, rs in by.items():
                    s = rs[0].series
                    err = s["pos"][:, i] - s["pos_des"][:, i]
                    lines[who] = ax.plot(s["t"], err, **_style(who, spec))[0]
                    peaks[who] = float(np.max(np.abs(err)))
                _off_scale(ax, lines, peaks, _limit(peaks))
                ax.set_ylabel(f"{'XYZ'[i]} error (m)")
                ax.legend(loc="upper right", ncol=3)
            axes[-1].set_xlabel("t (s)")
            fig.suptitle(f"Fig. 16 compared: tracking error on the line-then-helix of Eq. 46 ({where})")
        elif exp == "rectangle":
            fig, ax = plt.subplots(figsize=(8, 6))
            wp = np.asarray(next(iter(by.values()))[0].job.config()["guidance.waypoints"], dtype=float)
            lo, hi = wp[:, :2].min(axis=0) - 1.0, wp[:, :2].max(axis=0) + 1.0  # the rectangle and a metre around
            for who, rs in by.items():
                s = rs[0].series
                st = _style(who, spec)
                xy = s["pos"][:, :2]
                if np.any(xy < lo) or np.any(xy > hi):
                    st["label"] += " (leaves the plot)"
                ax.plot(xy[:, 0], xy[:, 1], **st)
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            for p in wp:
                ax.add_patch(plt.Circle((p[0], p[1]), paper_data.RECTANGLE_SWITCHING_RADIUS_M, fill=False,
                                        color="tab:red", lw=0.8))
            ax.plot(wp[:, 0], wp[:, 1], "k+", ms=10, label="waypoints (8 cm circles)")
            ax.set_xlabel("X east (m)")
            ax.set_ylabel("Y north (m)")
            ax.set_aspect("equal", adjustable="box")
            ax.legend(loc="center")
            ax.set_title(f"Fig. 19 compared: the waypoint rectangle, headless ({where})")
        else:
            continue
        fig.tight_layout()
        out.append(figures.save(fig, ctx.out_dir, FILES[exp]))
    return out
