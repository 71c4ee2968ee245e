"""PNG plots of a .tlog (Agg backend; needs matplotlib).

* ``attitude.png`` - phi, theta, psi against their targets (the paper's angles, degrees;
  ATTITUDE / ATTITUDE_TARGET through :func:`protocol.frames.mavlink_euler_to_paper`);
* ``xy_path.png`` - the XY path against the target path and the waypoints with their
  switching circles (like Fig. 19); waypoints from the log's MISSION_ITEM_INT messages or
  a mission file;
* ``position.png`` - X, Y, Z against time with their targets (like Fig. 16);
* ``thrusts.png`` - motor thrusts from HILMS_LOAD_CELLS (N, like Fig. 18) and the motor
  commands from SERVO_OUTPUT_RAW (us);
* ``load_cells.png`` - the load cells: raw ADC counts and force (gram-force);
* ``errors.png`` - the tracking errors against time: phi, theta, psi (deg) and X, Y, Z (m),
  actual minus the latest target (the samples of Eq. 45; the legend gives each mean |e|);
* ``path_3d.png`` - the flown path and the target path in 3D (X east, Y north, Z up; the
  helix of Eq. 46 as the paper's Fig. 16 shows it).

Every title names the run: scenario, strategy, airframe and seed from the log's ``run:``
STATUSTEXT (``protocol/run_label.py``; headless logs of ``rig-emulator simulate`` carry it),
else ``title`` (``rig-gcs plot --title``), else the log's file name.

Positions are the paper's world frame (X east, Y north, Z up, :func:`protocol.frames.ned_to_enu`);
time is the vehicle's clock (``time_boot_ms`` / ``time_usec``), in seconds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gcs_tools.errors import UsageError
from gcs_tools.missions import waypoints_enu
from gcs_tools.tlog_errors import attitude_series, position_series
from gcs_tools.tlog_read import iter_tlog, read_fields
from protocol.dialect import mavlink as M
from protocol.frames import mavlink_euler_to_paper
from protocol.geodesy import Home
from protocol.mission_files import Mission
from protocol.run_label import label_from_texts
from gcs_tools.mission_client import item_from_message

SPEC = {
    "ATTITUDE": ["time_boot_ms", "roll", "pitch", "yaw"],
    "ATTITUDE_TARGET": ["time_boot_ms", "type_mask", "q[0]", "q[1]", "q[2]", "q[3]"],
    "LOCAL_POSITION_NED": ["time_boot_ms", "x", "y", "z"],
    "POSITION_TARGET_LOCAL_NED": ["time_boot_ms", "type_mask", "x", "y", "z"],
    "HILMS_LOAD_CELLS": ["time_usec"] + [f"thrust_n[{i}]" for i in range(4)] + [f"raw_counts[{i}]" for i in range(4)]
                        + [f"force_grf[{i}]" for i in range(4)],
    "SERVO_OUTPUT_RAW": ["time_usec"] + [f"servo{i}_raw" for i in range(1, 5)],
    "HOME_POSITION": ["latitude", "longitude", "altitude"],
}
FIGURES = ("attitude", "xy_path", "position", "thrusts", "load_cells", "errors", "path_3d")


def _plt():
    try:
        import matplotlib
    except ImportError:
        raise UsageError("plotting needs matplotlib: pip install matplotlib") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def mission_from_tlog(path) -> Mission | None:
    """The mission items a log holds (MISSION_ITEM_INT / MISSION_ITEM by seq, the last copy wins)."""
    items = {}
    count = None
    for msg in iter_tlog(path, {"MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_COUNT"}):
        if getattr(msg, "mission_type", 0) != M.MAV_MISSION_TYPE_MISSION:
            continue
        if msg.get_type() == "MISSION_COUNT":
            count = msg.count
            continue
        items[msg.seq] = item_from_message(msg)
    if not items:
        return None
    n = count if count is not None else max(items) + 1
    if any(k not in items for k in range(n)):
        return None
    return Mission(tuple(items[k] for k in range(n)))


def run_label_from_tlog(path) -> str | None:
    """The run label of the log's ``run:`` STATUSTEXT (chunks of one ``id`` joined), or None."""
    texts: dict = {}
    for msg in iter_tlog(path, {"STATUSTEXT"}):
        text = msg.text if isinstance(msg.text, str) else msg.text.decode("ascii", "replace")
        key = (msg.get_srcSystem(), msg.id) if msg.id else object()
        texts[key] = texts.get(key, "") + text.rstrip("\x00")
    return label_from_texts(texts.values())


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def _layout(fig) -> None:
    """Fixed margins for every figure (a two-line title on top): ``tight_layout`` measured every
    text first, a fifth of the time of ``rig-gcs plot``."""
    w, h = fig.get_size_inches()
    fig.subplots_adjust(left=0.8 / w, right=1.0 - 0.25 / w, bottom=0.55 / h, top=1.0 - 0.75 / h, hspace=0.25)


def _save(fig, out: Path, name: str) -> Path:
    path = out / f"{name}.png"
    tmp = out / f".{name}.png.tmp"
    fig.savefig(tmp, dpi=110, format="png")
    tmp.replace(path)
    return path


def plot_tlog(path, out_dir, mission: Mission | None = None, title: str | None = None) -> tuple[list[Path], dict]:
    """Write the PNGs that the log's messages allow; returns (files written, {figure: reason skipped}).
    Titles name the run (module doc); ``title`` when the log does not."""
    plt = _plt()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    arrays, info = read_fields(path, SPEC)
    run = run_label_from_tlog(path) or title or Path(path).name
    named = lambda what: f"{what}\n{run}"  # noqa: E731
    counts = info["counts"]
    has = lambda *names: all(counts.get(n, 0) > 0 for n in names)  # noqa: E731
    written, skipped = [], {}

    # attitude
    if has("ATTITUDE"):
        a = arrays["ATTITUDE"]
        t = a["time_boot_ms"] * 1e-3
        actual = np.column_stack(mavlink_euler_to_paper(a["roll"], a["pitch"], a["yaw"]))
        target = None
        if has("ATTITUDE_TARGET"):
            s = attitude_series(arrays)
            target = np.column_stack(mavlink_euler_to_paper(s["target"][:, 0], s["target"][:, 1], s["target"][:, 2]))
        fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
        for i, (ax, name) in enumerate(zip(axes, ("phi", "theta", "psi"))):
            ax.plot(t, np.degrees(actual[:, i]), lw=1.0, label=f"{name}")
            if target is not None:
                ax.plot(t, np.degrees(target[:, i]), "--", lw=1.0, label=f"{name} desired")
            ax.set_ylabel(f"{name} (deg)")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8)
        axes[-1].set_xlabel("t (s)")
        fig.suptitle(named("Attitude vs target"))
        _layout(fig)
        written.append(_save(fig, out, "attitude"))
        plt.close(fig)
    else:
        skipped["attitude"] = "no ATTITUDE"

    # positions
    if has("LOCAL_POSITION_NED"):
        if has("POSITION_TARGET_LOCAL_NED"):
            s = position_series(arrays)
        else:
            p = arrays["LOCAL_POSITION_NED"]
            from protocol.frames import ned_to_enu

            s = {"t": p["time_boot_ms"] * 1e-3, "actual": ned_to_enu(np.column_stack([p["x"], p["y"], p["z"]])),
                 "target": None}
        fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
        for i, (ax, name) in enumerate(zip(axes, "XYZ")):
            ax.plot(s["t"], s["actual"][:, i], lw=1.0, label=name)
            if s["target"] is not None:
                ax.plot(s["t"], s["target"][:, i], "--", lw=1.0, label=f"{name} desired")
            ax.set_ylabel(f"{name} (m)")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper left", fontsize=8)
        axes[-1].set_xlabel("t (s)")
        fig.suptitle(named("Position vs time (X east, Y north, Z up)"))
        _layout(fig)
        written.append(_save(fig, out, "position"))
        plt.close(fig)

        if mission is None:
            mission = mission_from_tlog(path)
        home = None
        if has("HOME_POSITION"):
            h = arrays["HOME_POSITION"]
            home = Home(h["latitude"][-1] * 1e-7, h["longitude"][-1] * 1e-7, h["altitude"][-1] * 1e-3)
        fig, ax = plt.subplots(figsize=(7, 7))
        ax.plot(s["actual"][:, 0], s["actual"][:, 1], lw=1.0, label="path")
        if s["target"] is not None:
            ax.plot(s["target"][:, 0], s["target"][:, 1], "--", lw=1.0, label="target")
        if mission is not None and mission.items:
            pts, radii = waypoints_enu(mission, home)
            ax.plot(pts[:, 0], pts[:, 1], "k+", ms=10, label="waypoints")
            for k, (p, r) in enumerate(zip(pts, radii)):
                ax.add_patch(plt.Circle((p[0], p[1]), r, fill=False, color="r", lw=0.8))
                ax.annotate(str(k), (p[0], p[1]), textcoords="offset points", xytext=(6, 6), fontsize=8)
            ax.plot([], [], "r-", lw=0.8, label=f"switching circles (r = {radii[0]:g} m)")
        ax.set_xlabel("X east (m)")
        ax.set_ylabel("Y north (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
        ax.set_title(named("XY path" + (" and waypoints" if mission is not None else "")))
        _layout(fig)
        written.append(_save(fig, out, "xy_path"))
        plt.close(fig)
    else:
        skipped["position"] = skipped["xy_path"] = "no LOCAL_POSITION_NED"

    # errors against time (actual - latest target, as Eq. 45 pairs them)
    panels = []
    if has("ATTITUDE", "ATTITUDE_TARGET"):
        s_att = attitude_series(arrays)
        act = np.column_stack(mavlink_euler_to_paper(*s_att["actual"].T))
        tgt = np.column_stack(mavlink_euler_to_paper(*s_att["target"].T))
        panels.append((s_att["t"], np.degrees(_wrap(act - tgt)), ("phi", "theta", "psi"), "deg", "attitude error"))
    if has("LOCAL_POSITION_NED", "POSITION_TARGET_LOCAL_NED"):
        s_pos = position_series(arrays)
        panels.append((s_pos["t"], s_pos["actual"] - s_pos["target"], ("X", "Y", "Z"), "m", "position error"))
    if panels:
        fig, axes = plt.subplots(len(panels), 1, figsize=(9, 3.5 * len(panels)), sharex=True, squeeze=False)
        for ax, (t, err, names, unit, what) in zip(axes[:, 0], panels):
            for i, name in enumerate(names):
                e = err[:, i]
                mean = np.nanmean(np.abs(e)) if np.any(np.isfinite(e)) else np.nan
                ax.plot(t, e, lw=0.8, label=f"e_{name} (mean |e| {mean:.4g} {unit})")
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_ylabel(f"{what} ({unit})")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8)
        axes[-1, 0].set_xlabel("t (s)")
        fig.suptitle(named("Tracking errors (actual - desired) vs time"))
        _layout(fig)
        written.append(_save(fig, out, "errors"))
        plt.close(fig)
    else:
        skipped["errors"] = "no ATTITUDE with ATTITUDE_TARGET nor LOCAL_POSITION_NED with POSITION_TARGET_LOCAL_NED"

    # 3D path (the helix of Eq. 46, Fig. 16)
    if has("LOCAL_POSITION_NED"):
        fig = plt.figure(figsize=(8, 7))
        ax = fig.add_subplot(projection="3d")
        if s["target"] is not None:
            ax.plot(s["target"][:, 0], s["target"][:, 1], s["target"][:, 2], "--", lw=1.0, label="desired")
        ax.plot(s["actual"][:, 0], s["actual"][:, 1], s["actual"][:, 2], lw=1.0, label="flown")
        ax.set_xlabel("X east (m)")
        ax.set_ylabel("Y north (m)")
        ax.set_zlabel("Z up (m)")
        ax.legend(loc="upper left", fontsize=8)
        ax.set_title(named("3D path"))
        _layout(fig)
        written.append(_save(fig, out, "path_3d"))
        plt.close(fig)
    else:
        skipped["path_3d"] = "no LOCAL_POSITION_NED"

    # thrusts
    if has("HILMS_LOAD_CELLS") or has("SERVO_OUTPUT_RAW"):
        panels = [n for n in ("HILMS_LOAD_CELLS", "SERVO_OUTPUT_RAW") if has(n)]
        fig, axes = plt.subplots(len(panels), 1, figsize=(9, 3.5 * len(panels)), sharex=True, squeeze=False)
        for ax, name in zip(axes[:, 0], panels):
            d = arrays[name]
            t = d["time_usec"] * 1e-6
            for i in range(4):
                if name == "HILMS_LOAD_CELLS":
                    ax.plot(t, d[f"thrust_n[{i}]"], lw=0.8, label=f"F{i + 1}")
                else:
                    ax.plot(t, d[f"servo{i + 1}_raw"], lw=0.8, label=f"motor {i + 1}")
            ax.set_ylabel("thrust (N)" if name == "HILMS_LOAD_CELLS" else "PWM (us)")
            ax.set_title("Motor thrusts (load cells)" if name == "HILMS_LOAD_CELLS" else "Motor commands (SERVO_OUTPUT_RAW)",
                         fontsize=10)
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8, ncol=4)
        axes[-1, 0].set_xlabel("t (s)")
        fig.suptitle(named("Motors"))
        _layout(fig)
        written.append(_save(fig, out, "thrusts"))
        plt.close(fig)
    else:
        skipped["thrusts"] = "no HILMS_LOAD_CELLS or SERVO_OUTPUT_RAW"

    if has("HILMS_LOAD_CELLS"):
        d = arrays["HILMS_LOAD_CELLS"]
        t = d["time_usec"] * 1e-6
        fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
        for i in range(4):
            axes[0].plot(t, d[f"raw_counts[{i}]"], lw=0.8, label=f"cell {i + 1}")
            axes[1].plot(t, d[f"force_grf[{i}]"], lw=0.8, label=f"cell {i + 1}")
        axes[0].set_ylabel("raw (ADC counts)")
        axes[1].set_ylabel("force (gr.F)")
        axes[1].set_xlabel("t (s)")
        for ax in axes:
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8, ncol=4)
        fig.suptitle(named("Load cells"))
        _layout(fig)
        written.append(_save(fig, out, "load_cells"))
        plt.close(fig)
    else:
        skipped["load_cells"] = "no HILMS_LOAD_CELLS"
    return written, skipped
