"""Arm the served hardware rig from its tilted hang into a mission take-off and watch both positions.

    python -m gcs_tools.studies served-takeoff [--contact hold|frictionless] [--seconds 25] [--seed 0] [--runs N]
    python -m gcs_tools.studies served-takeoff --runs 4 --markdown docs/generated/served-takeoff.md

A rig (``hilms``, the default plant, hanging at its rest attitude) is served in this process and
flown over a real socket from pymavlink: a mission of a take-off to 2.5 m and a 20 s hold at home
is uploaded, the mode set to AUTO.MISSION, the rig armed. For ``--seconds`` of simulated time the
script records LOCAL_POSITION_NED (the onboard position) and SIM_STATE (the physics vehicle) and
prints, for each, the largest horizontal distance from home, that distance while the vehicle is
within 5 cm of the ground, the position at the end and when it left the ground; and every
STATUSTEXT. ``--contact frictionless`` flies the same with the ideal plant's ground
(docs/explanation/sim-state.md). ``--markdown FILE`` flies both ground contacts ``--runs`` times each
and writes the ranges over the runs as the page that docs/explanation/sim-state.md includes.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from gcs_tools.studies.page import span
from protocol.dialect import mavlink as M
from protocol.geodesy import global_to_local_ned
from protocol.mission_items import MissionItem
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, stamp_s

ENU = M.MAV_FRAME_LOCAL_ENU


def fly_once(contact: str, seconds: float, seed: int, quiet: bool = False) -> dict:
    """One served take-off from the hang: per vehicle, the largest horizontal distance from home, that
    distance within 5 cm of the ground, the position at the end and when it left the ground (s after
    the first LOCAL_POSITION_NED after arming, or None)."""
    overrides = {"sim.ground_contact": contact, "sim.seed": seed}
    with RigThread(speedup=0.0, airframe="hilms", overrides=overrides) as rig:
        home = rig.server.ctx.home
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert recv(conn, "HEARTBEAT", 60) is not None
        items = [MissionItem(seq=0, frame=ENU, command=M.MAV_CMD_NAV_TAKEOFF, current=1, z=2.5),
                 MissionItem(seq=1, frame=ENU, command=M.MAV_CMD_NAV_WAYPOINT, x=0.0, y=0.0, z=2.5, param1=20.0)]
        assert MissionClient(conn).upload(items) == M.MAV_MISSION_ACCEPTED
        att = recv(conn, "ATTITUDE", 30)
        if not quiet:
            print(f"hanging at roll {math.degrees(att.roll):.1f} deg, pitch {math.degrees(att.pitch):.1f} deg; "
                  f"ground contact {contact}")
        assert command(conn, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 4).result == 0
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == 0
        t0 = None
        onboard, physics = [], []
        n = 0
        while not onboard or onboard[-1][0] - t0 < seconds:
            m = recv(conn, ["LOCAL_POSITION_NED", "SIM_STATE", "STATUSTEXT"], 30)
            if m is None:
                break
            n += 1
            if n % 200 == 0:
                conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            if m.get_type() == "STATUSTEXT":
                if not quiet:
                    print("STATUSTEXT", m.text)
            elif m.get_type() == "LOCAL_POSITION_NED":
                t = stamp_s(m)
                t0 = t if t0 is None else t0
                onboard.append((t, m.x, m.y, m.z))
            elif onboard:  # SIM_STATE carries no time stamp: the last LOCAL_POSITION_NED's
                physics.append((onboard[-1][0], *global_to_local_ned(home, m.lat_int * 1e-7, m.lon_int * 1e-7, m.alt)))
        conn.close()
    out = {}
    for name, rows in (("onboard", onboard), ("physics", physics)):
        a = np.array(rows)
        h = np.hypot(a[:, 1], a[:, 2])
        low = a[:, 3] > -0.05
        up = a[~low, 0]
        out[name] = {"max_m": float(h.max()), "on_ground_max_m": float(h[low].max()) if low.any() else 0.0,
                     "end_ned": a[-1, 1:4].tolist(), "end_m": float(h[-1]),
                     "left_s": float(up[0] - t0) if up.size else None}
    return out


def _report(contact: str, r: dict) -> None:
    for name, what in (("onboard", "onboard (LOCAL_POSITION_NED)"), ("physics", "physics (SIM_STATE)")):
        v = r[name]
        n, e, d = v["end_ned"]
        left = f"{v['left_s']:.2f} s" if v["left_s"] is not None else "never"
        print(f"{what}: largest horizontal distance from home {v['max_m']:.3f} m, within 5 cm of the ground "
              f"{v['on_ground_max_m']:.3f} m; at the end N {n:+.2f} E {e:+.2f} D {d:+.2f}; left the ground at {left}")


def markdown(results: dict, command: str, machine: str, seconds: float, seed: int) -> str:
    """The page docs/explanation/sim-state.md includes: per ground contact, the ranges over the runs."""
    runs = len(next(iter(results.values())))
    lines = [f"Written by `{command}` on {machine}: the served `hilms` rig armed from its hang into a mission "
             f"take-off to 2.5 m, seed {seed}, {seconds:g} s of simulated time after arming, {runs} "
             f"run{'s' if runs != 1 else ''} per ground contact (they differ because the served rig's clock runs on while the arm command travels); "
             "ranges over the runs.", "",
             "| ground contact | vehicle | leaves the ground after (s) | largest distance from home (m) | "
             "distance while within 5 cm of the ground (m) | distance from home at the end (m) |",
             "| --- | --- | --- | --- | --- | --- |"]
    for contact, rs in results.items():
        for name, what in (("onboard", "onboard (LOCAL_POSITION_NED)"), ("physics", "physics (SIM_STATE)")):
            vs = [r[name] for r in rs]
            left = [v["left_s"] for v in vs if v["left_s"] is not None]
            left_txt = span(left, 2) if left else "never"
            if len(left) < len(vs) and left:
                left_txt += f" ({len(vs) - len(left)} never)"
            lines.append(f"| `{contact}` | {what} | {left_txt} | {span([v['max_m'] for v in vs], 3)} | "
                         f"{span([v['on_ground_max_m'] for v in vs], 3)} | {span([v['end_m'] for v in vs], 3)} |")
    return "\n".join(lines) + "\n"


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies served-takeoff",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--contact", choices=("hold", "frictionless"), default="hold", help="sim.ground_contact")
    ap.add_argument("--seconds", type=float, default=25.0, help="simulated seconds recorded after arming")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--runs", type=int, default=1, help="take-offs per ground contact")
    ap.add_argument("--markdown", metavar="FILE",
                    help="fly both ground contacts --runs times each and write the ranges as a documentation page")
    return ap


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    if not args.markdown:
        for _ in range(args.runs):
            _report(args.contact, fly_once(args.contact, args.seconds, args.seed))
        return 0
    from gcs_tools.studies.page import command_line, machine

    results = {c: [fly_once(c, args.seconds, args.seed, quiet=True) for _ in range(args.runs)]
               for c in ("hold", "frictionless")}
    for c, rs in results.items():
        for r in rs:
            _report(c, r)
    text = markdown(results, command_line(["python -m gcs_tools.studies served-takeoff", *sys.argv[1:]]), machine(),
                    args.seconds, args.seed)
    with open(args.markdown, "w") as f:
        f.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
