"""Fig. 19: the 5 m x 3 m waypoint rectangle with 8 cm switching, flown through the MAVLink
mission path (:mod:`gcs_tools.reproduce.live_rectangle`), SMC-FLC.

The mean errors in X and Y (Eq. 45, the rig's own position against the virtual line it
follows) are taken from the start until the last waypoint is reached (the whole run if it
is not), where the paper's rig was flying. The same scenario run headless
(``rectangle``) is shown next to it as a cross-check of the MAVLink path.
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.reproduce import figures, paper_data
from gcs_tools.reproduce.experiment import NOT_REPRODUCED, REPRODUCED, Context, Section, Verdict, fmt, status_of, table
from gcs_tools.reproduce.metrics import window_mean_abs

NAME = "rectangle"
TITLE = "Waypoint rectangle flown over MAVLink"
PAPER = "Sec. 4-4, Fig. 19"
STRATEGY = "smc-flc"
DURATION_S = 60.0
QUICK_S = 40.0  # long enough to reach every waypoint (the last at about 36 s)
SAME_ORDER = 2.0  # the paper's mean errors "reproduced" when ours are within a factor of 2


def duration(ctx: Context) -> float:
    return QUICK_S if ctx.quick else DURATION_S


def jobs(ctx: Context) -> list:
    return [ctx.job("rectangle", STRATEGY, duration=duration(ctx),
                   columns=("t", "pos", "pos_des", "waypoint"), label=f"{NAME}/headless")]


def live(ctx: Context):
    from gcs_tools.reproduce.live_rectangle import fly_rectangle  # pymavlink's dialect: loaded when flown

    w, h = paper_data.RECTANGLE_SIZE_M
    return fly_rectangle(ctx.seed, duration(ctx), STRATEGY, w, h, paper_data.RECTANGLE_SWITCHING_RADIUS_M,
                         airframe=ctx.airframe, overrides=dict(ctx.overrides))


def headless_live(ctx: Context, result):
    """A :class:`~gcs_tools.reproduce.live_rectangle.LiveRun` made of the headless run, for the
    plants and seeds of a reproduction that are not flown over MAVLink (``rig-gcs reproduce``
    flies the first plant's first seed only): the same scenario, the rig's own position."""
    from gcs_tools.reproduce.live_rectangle import LiveRun

    s = result.series
    wp = np.asarray(result.job.config()["guidance.waypoints"], dtype=float)
    reached = [(k, float(t)) for k, t in enumerate(result.reached_t) if np.isfinite(t)]
    return LiveRun(waypoints=wp, radius_m=paper_data.RECTANGLE_SWITCHING_RADIUS_M, duration_s=duration(ctx),
                   t_pos=s["t"], pos=s["pos"], pos_target=s["pos_des"], t_att=s["t"], euler=np.zeros((s["t"].size, 3)),
                   euler_target=np.zeros((s["t"].size, 3)), reached=reached, stream_hz=0.0, messages=0,
                   rig_exit_code=0)


def _errors(t, pos, target, t_end) -> dict:
    return {k: window_mean_abs(t, pos[:, i], target[:, i], t[0], t_end) for i, k in enumerate(("x_m", "y_m", "z_m"))}


def analyse(ctx: Context, results: list, live) -> Section:
    n_wp = live.waypoints.shape[0]
    reached = {seq: t for seq, t in live.reached}
    all_reached = all(k in reached for k in range(n_wp))
    t_end = max(reached.values()) if all_reached else float(live.t_pos[-1])
    me_live = _errors(live.t_pos, live.pos, live.pos_target, t_end)
    head = results[0]
    hs = head.series
    h_reached = head.reached_t
    h_end = float(np.nanmax(h_reached)) if np.all(np.isfinite(h_reached)) else float(hs["t"][-1])
    me_head = _errors(hs["t"], hs["pos"], hs["pos_des"], h_end)
    p = paper_data.RECTANGLE_ME
    rows = [["MAVLink rig (ours)", f"{len(reached)}/{n_wp}", fmt(t_end, 2), fmt(me_live["x_m"], 4),
             fmt(me_live["y_m"], 4), fmt(me_live["z_m"], 4)],
            ["headless twin (ours)", f"{int(np.isfinite(h_reached).sum())}/{h_reached.size}", fmt(h_end, 2),
             fmt(me_head["x_m"], 4), fmt(me_head["y_m"], 4), fmt(me_head["z_m"], 4)],
            ["paper", "all", "-", fmt(p["x_m"], 4), fmt(p["y_m"], 5), "-"]]
    times = ", ".join(f"{seq}: {fmt(t, 2)} s" for seq, t in sorted(reached.items()))
    body = "\n".join([
        f"SMC-FLC, a rig process (`rig-emulator serve --start-paused --speedup max`) flown by a ground station over "
        f"TCP for {duration(ctx):g} simulated seconds: the {paper_data.RECTANGLE_SIZE_M[0]:g} m x "
        f"{paper_data.RECTANGLE_SIZE_M[1]:g} m rectangle at 2 m uploaded as MISSION_ITEM_INT items with an "
        f"{paper_data.RECTANGLE_SWITCHING_RADIUS_M * 100:g} cm acceptance radius, armed, MAV_CMD_MISSION_START; "
        f"figures from {live.messages} telemetry messages stamped in simulated time ({live.stream_hz:g} Hz). Waypoints reached "
        f"(MISSION_ITEM_REACHED): {times or 'none'}. Mean errors against the virtual line from the start to the "
        "last waypoint:",
        "",
        table(["run", "waypoints reached", "window end (s)", "ME X (m)", "ME Y (m)", "ME Z (m)"], rows),
    ])
    ratio = {k: p[k] / me_live[k] if me_live[k] > 0 else math.inf for k in ("x_m", "y_m")}
    same = all(1.0 / SAME_ORDER <= r <= SAME_ORDER for r in ratio.values())
    verdicts = [
        Verdict("rectangle_all_waypoints", REPRODUCED if all_reached else NOT_REPRODUCED,
                f"{len(reached)}/{n_wp} waypoints reached over MAVLink within {fmt(live.duration_s, 0)} s"
                + (f", the last at {fmt(t_end, 2)} s" if all_reached else "")),
        Verdict("rectangle_mean_errors", status_of(same),
                f"ours {fmt(me_live['x_m'], 4)} / {fmt(me_live['y_m'], 4)} m vs the paper's {p['x_m']} / {p['y_m']} m "
                f"(X / Y): the paper's are {fmt(ratio['x_m'], 1)}x and {fmt(ratio['y_m'], 1)}x ours "
                f"(read as the same within a factor of {SAME_ORDER:g})"),
    ]
    numbers = {"reached_s": {str(k): v for k, v in sorted(reached.items())}, "window_end_s": t_end,
               "mean_errors_mavlink": me_live, "mean_errors_headless": me_head, "headless_window_end_s": h_end,
               "headless_reached_s": {str(k): float(v) for k, v in enumerate(h_reached) if np.isfinite(v)},
               "telemetry_messages": live.messages}
    return Section(NAME, TITLE, PAPER, body, [_figure(ctx, live, hs)], numbers, verdicts)


def _figure(ctx: Context, live, hs) -> str:
    plt = figures.pyplot()
    fig, ax = plt.subplots(figsize=(8, 6))
    ax.plot(hs["pos"][:, 0], hs["pos"][:, 1], color="tab:gray", lw=0.8, label="headless twin")
    ax.plot(live.pos[:, 0], live.pos[:, 1], color=figures.COLORS[STRATEGY], label="MAVLink rig (LOCAL_POSITION_NED)")
    ax.plot(live.pos_target[:, 0], live.pos_target[:, 1], "--", color="black", lw=0.8,
            label="virtual line (POSITION_TARGET_LOCAL_NED)")
    for k, p in enumerate(live.waypoints):
        ax.add_patch(plt.Circle((p[0], p[1]), live.radius_m, fill=False, color="tab:red", lw=0.8))
        ax.annotate(str(k), (p[0], p[1]), textcoords="offset points", xytext=(6, 6))
    ax.plot(live.waypoints[:, 0], live.waypoints[:, 1], "k+", ms=10, label="waypoints (8 cm circles)")
    ax.set_xlabel("X east (m)")
    ax.set_ylabel("Y north (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="center")
    ax.set_title("Fig. 19 (emulated): the waypoint rectangle, SMC-FLC")
    fig.tight_layout()
    return figures.save(fig, ctx.out_dir, "fig19_rectangle.png")
