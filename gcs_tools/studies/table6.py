"""Table 6's altitude errors on the hardware rig through the mixer: under the roll/pitch-first mixer
(``control.allocation_priority = "attitude"``) the FLC's is metres where the paper's two are equal
(0.2279 / 0.2263 m); and the rectangle's ME Y (docs/explanation/readings.md, "The mixer when the
motors saturate"; the ``bias`` scan in docs/explanation/paper-fit.md).

    python -m gcs_tools.studies table6 candidates --priority attitude [--workers N]   # each candidate switched off
    python -m gcs_tools.studies table6 candidates --priority thrust [--workers N]     # the same, the shipped mixer
    python -m gcs_tools.studies table6 candidates --priority clip --shipped-only   # per-motor clipping, first row
    python -m gcs_tools.studies table6 priority [--workers N]     # the allocation's priority x CoG height
    python -m gcs_tools.studies table6 priority --priorities clip --cog-mm 0,10,20   # the third reading
    python -m gcs_tools.studies table6 bias [--workers N]         # the common thrust bias: both Z within x2?
    python -m gcs_tools.studies table6 rectangle [--workers N]    # the rectangle's ME X / Y per leg direction
    python -m gcs_tools.studies table6 priority --markdown FILE   # also write the table as a docs page

Every row is the mean over seeds 0-2 of the 60 s helix (Eq. 46) on ``hilms`` with the named
overrides (``candidates``: on top of ``control.allocation_priority`` = ``--priority``, default
"attitude", the mixer before this study). "Z outside 12-20 s" is Eq. 45 over the samples before Eq. 46's X/Y jump at t = 12 s and
after 20 s; "jump window" is the rest of ME Z (the 12-20 s samples' share of the 60 s mean);
"u1 given up" is the mixer's: the share of the 12-16 s control updates logged with the
allocation's SATURATED_COLLECTIVE flag (u1 shifted to make room for roll/pitch) and the largest
vertical-velocity deficit (v_Z,des - v_Z) over 12-16 s.
"""

import argparse

import numpy as np

from rig_emulator.control.allocation import SATURATED_COLLECTIVE
from gcs_tools.studies.page import Page
from rig_emulator.sweep import SimJob, run_jobs

SEEDS = (0, 1, 2)
Z3 = [0.0, 0.0, 0.0]
JUMP = (12.0, 20.0)

CANDIDATES = {
    "hilms as shipped (T = 200 s)": {},
    "thrust loop off (T = 0)": {"motors.thrust_loop_time_constant": 0.0},
    "motor curve linear (n = 1)": {"motors.curve_exponent": 1.0},
    "no common thrust bias": {"motors.thrust_bias_grf": 0.0},
    "equal motor gains": {"motors.thrust_gain": [1.0, 1.0, 1.0, 1.0]},
    "no command quantisation": {"motors.command_steps": 0},
    "no ESC dead-band": {"motors.esc_deadband_v": 0.0},
    "no actuation delay": {"control.actuation_delay": 0.0},
    "no random torque": {"disturbance.torque_noise": Z3},
    "no frame vibration": {"vibration.gyro_amplitude": Z3, "vibration.accel_amplitude": Z3},
    "no joint friction": {"joint.viscous": Z3, "joint.coulomb": Z3},
    "CoG at the joint": {"joint.cog_offset": Z3},
    "position rate share 1": {"flc.position_rate_share": 1.0},
    "true attitude fed back": {"sensors.feedback": "ideal"},
}


def _reduce(job, r):
    s = r.series
    t = s["t"]
    ez = np.abs(s["pos"][:, 2] - s["pos_des"][:, 2])
    out = r.mean_errors()
    jw = (t >= JUMP[0]) & (t < JUMP[1])
    out["z_outside"] = float(np.mean(ez[~jw]))
    out["z_jump_share"] = float(np.sum(ez[jw]) / len(t))
    out["drop"] = float(np.max((s["pos_des"][:, 2] - s["pos"][:, 2])[jw]))
    w = (t >= 12.0) & (t < 16.0)
    out["coll_sat"] = float(np.mean((s["flags"][w].astype(np.int64) & SATURATED_COLLECTIVE) != 0))
    out["vz_deficit"] = float(np.max(s["vel_des"][w, 2] - s["vel"][w, 2]))
    out["failsafe"] = int(np.max(s["failsafe"]) > 0)
    return out


def _run(settings, workers, strategies=("flc", "smc-flc"), scenario="helix", reduce=_reduce):
    jobs = [SimJob(scenario, st, sd, overrides=ov, label=f"{name}|{st}")
            for name, ov in settings.items() for st in strategies for sd in SEEDS]
    res = run_jobs(jobs, workers=workers, reduce=reduce)
    out = {}
    for j, r in zip(jobs, res):
        out.setdefault(j.label, []).append(r)
    return out


def _m(rows, k):
    return float(np.mean([r[k] for r in rows]))


def candidates(workers, settings=None, priority="attitude", out=None):
    out = out or Page(None)
    settings = CANDIDATES if settings is None else settings
    settings = {name: {"control.allocation_priority": priority, **ov} for name, ov in settings.items()}
    res = _run(settings, workers)
    out.print("| switched off / changed | ME Z FLC | ME Z SMC-FLC | ratio | Z outside 12-20 s FLC / SMC-FLC | "
          "jump window FLC / SMC-FLC | largest drop below Z_des 12-20 s FLC / SMC-FLC (m) | "
          "u1 shifted 12-16 s FLC / SMC-FLC | largest v_Z deficit 12-16 s FLC / SMC-FLC (m/s) | ME theta FLC / SMC-FLC (deg) |")
    out.print("|---|---|---|---|---|---|---|---|---|---|")
    for name in settings:
        a, b = res[f"{name}|flc"], res[f"{name}|smc-flc"]
        fs = sum(r["failsafe"] for r in a + b)
        out.print(f"| {name} | {_m(a, 'z_m'):.3f} | {_m(b, 'z_m'):.3f} | {_m(a, 'z_m') / _m(b, 'z_m'):.2f} | "
              f"{_m(a, 'z_outside'):.3f} / {_m(b, 'z_outside'):.3f} | {_m(a, 'z_jump_share'):.3f} / "
              f"{_m(b, 'z_jump_share'):.3f} | {_m(a, 'drop'):.2f} / {_m(b, 'drop'):.2f} | "
              f"{_m(a, 'coll_sat') * 100:.0f} % / {_m(b, 'coll_sat') * 100:.0f} % | "
              f"{_m(a, 'vz_deficit'):.2f} / {_m(b, 'vz_deficit'):.2f} | {_m(a, 'theta_deg'):.3f} / "
              f"{_m(b, 'theta_deg'):.3f}{f' ({fs} failsafe trips)' if fs else ''} |")


def priority(workers, priorities=("attitude", "thrust"), cog_mm=(0.0, 10.0, 20.0, 35.0, 50.0), out=None):
    out = out or Page(None)
    settings = {f"{p}, CoG {cz:g} mm below": {"control.allocation_priority": p,
                                                "joint.cog_offset": [0.008, -0.008, cz * 1e-3]}
                for p in priorities for cz in cog_mm}
    res = _run(settings, workers, strategies=("flc",))
    out.print("| allocation priority, CoG height | FLC ME Z per seed (m) | FLC ME theta per seed (deg) | failsafe trips |")
    out.print("|---|---|---|---|")
    for name in settings:
        a = res[f"{name}|flc"]
        zs = ", ".join("%.3f" % r["z_m"] for r in a)
        ths = ", ".join("%.2f" % r["theta_deg"] for r in a)
        out.print(f"| {name} | {zs} | {ths} | {sum(r['failsafe'] for r in a)} of {len(a)} |")


def bias(workers, priority="attitude", out=None):
    candidates(workers, {f"thrust bias {b:g} gr.F": {"motors.thrust_bias_grf": b}
                         for b in (0.0, -25.0, -50.0, -60.0, -70.0, -85.0, -100.0)}, priority, out)


def _rect_reduce(job, r):
    s = r.series
    t, wp = s["t"], s["waypoint"]
    e = np.abs(s["pos"][:, :2] - s["pos_des"][:, :2])
    reached = r.reached_t[np.isfinite(r.reached_t)] if len(r.reached_t) else np.array([])
    end = float(reached[-1]) if len(reached) else float(t[-1])
    m = t <= end
    v = s["vel_des"][:, :2]
    along_x = m & (np.abs(v[:, 0]) > np.abs(v[:, 1]))  # legs flown along X (5 m)
    along_y = m & ~along_x
    n = np.count_nonzero(m)
    return {"x": float(e[m, 0].mean()), "y": float(e[m, 1].mean()),
            "x_on_x": float(e[along_x, 0].sum() / n), "x_on_y": float(e[along_y, 0].sum() / n),
            "y_on_x": float(e[along_x, 1].sum() / n), "y_on_y": float(e[along_y, 1].sum() / n),
            "share_x_legs": float(np.count_nonzero(along_x) / n), "wp": float(np.max(wp))}


def rectangle(workers, out=None):
    out = out or Page(None)
    settings = {"hilms": {}, "position rate share 1": {"flc.position_rate_share": 1.0},
                "leg speed 0.75 m/s": {"guidance.speed": 0.75}}
    res = _run(settings, workers, strategies=("smc-flc",), scenario="rectangle", reduce=_rect_reduce)
    out.print("| setting | ME X | ME Y | Y / X | X error: on X legs + on Y legs | Y error: on X legs + on Y legs | "
          "time on the 5 m legs |")
    out.print("|---|---|---|---|---|---|---|")
    for name in settings:
        a = res[f"{name}|smc-flc"]
        out.print(f"| {name} | {_m(a, 'x'):.4f} | {_m(a, 'y'):.4f} | {_m(a, 'y') / _m(a, 'x'):.2f} | "
              f"{_m(a, 'x_on_x'):.4f} + {_m(a, 'x_on_y'):.4f} | {_m(a, 'y_on_x'):.4f} + {_m(a, 'y_on_y'):.4f} | "
              f"{_m(a, 'share_x_legs') * 100:.0f} % |")


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies table6", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", choices=("candidates", "priority", "bias", "rectangle"))
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--priority", choices=("attitude", "thrust", "clip"), default="attitude",
                    help="control.allocation_priority under the candidates and bias rows")
    ap.add_argument("--shipped-only", action="store_true",
                    help="candidates: only the first row (hilms as shipped)")
    ap.add_argument("--priorities", default="attitude,thrust",
                    help="priority: the control.allocation_priority values, comma-separated")
    ap.add_argument("--cog-mm", default="0,10,20,35,50",
                    help="priority: the CoG heights below the joint (mm), comma-separated")
    ap.add_argument("--markdown", metavar="FILE", help="also write the table to FILE, with the command and the machine")
    return ap


#: what each study's table holds, for the page ``--markdown`` writes
WHAT = {
    "candidates": "Mean of seeds 0-2 of the 60 s helix (Eq. 46) on `hilms` with `control.allocation_priority` = "
                  "`{priority}` and each row's change; ME in metres and degrees (Eq. 45).",
    "bias": "Mean of seeds 0-2 of the 60 s helix (Eq. 46) on `hilms` with `control.allocation_priority` = "
            "`{priority}` per common thrust bias; ME in metres and degrees (Eq. 45).",
    "priority": "The FLC on the 60 s helix (Eq. 46) on `hilms`, seeds 0-2, per allocation priority and height of "
                "the centre of gravity below the joint.",
    "rectangle": "The SMC-FLC on the headless rectangle (Sec. 4-4) on `hilms`, mean of seeds 0-2, until the last "
                 "waypoint; errors in metres.",
}


def main(argv=None):
    a = parser().parse_args(argv)
    out = Page(a.markdown, WHAT[a.study].format(priority=a.priority), workers=a.workers)
    if a.study == "candidates":
        rows = {k: v for k, v in list(CANDIDATES.items())[:1]} if a.shipped_only else None
        candidates(a.workers, rows, priority=a.priority, out=out)
    elif a.study == "bias":
        bias(a.workers, priority=a.priority, out=out)
    elif a.study == "priority":
        priority(a.workers, tuple(a.priorities.split(",")), tuple(float(c) for c in a.cog_mm.split(",")), out=out)
    else:
        rectangle(a.workers, out=out)
    out.write()

if __name__ == "__main__":
    main()
