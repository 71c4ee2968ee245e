"""Arm the served hardware rig from its tilted hang into a mission take-off and watch both positions.

    python scripts/measure_ground.py [--contact hold|frictionless] [--seconds 25] [--seed 0]

A rig (``hilms``, the default plant, hanging at its rest attitude) is served in this process and
flown over a real socket from pymavlink: a mission of a take-off to 2.5 m and a 20 s hold at home
is uploaded, the mode set to AUTO.MISSION, the rig armed. For ``--seconds`` of simulated time the
script records LOCAL_POSITION_NED (the onboard position) and SIM_STATE (the physics vehicle) and
prints, for each, the largest horizontal distance from home, that distance while the vehicle is
within 5 cm of the ground, the position at the end and when it left the ground; and every
STATUSTEXT. ``--contact frictionless`` flies the same with the ideal plant's ground
(docs/explanation/sim-state.md).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from protocol.dialect import mavlink as M
from protocol.geodesy import global_to_local_ned
from protocol.mission_items import MissionItem
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, stamp_s

ENU = M.MAV_FRAME_LOCAL_ENU


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--contact", choices=("hold", "frictionless"), default="hold", help="sim.ground_contact")
    ap.add_argument("--seconds", type=float, default=25.0, help="simulated seconds recorded after arming")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    overrides = {"sim.ground_contact": args.contact, "sim.seed": args.seed}
    with RigThread(speedup=0.0, airframe="hilms", overrides=overrides) as rig:
        home = rig.server.ctx.home
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert recv(conn, "HEARTBEAT", 60) is not None
        items = [MissionItem(seq=0, frame=ENU, command=M.MAV_CMD_NAV_TAKEOFF, current=1, z=2.5),
                 MissionItem(seq=1, frame=ENU, command=M.MAV_CMD_NAV_WAYPOINT, x=0.0, y=0.0, z=2.5, param1=20.0)]
        assert MissionClient(conn).upload(items) == M.MAV_MISSION_ACCEPTED
        att = recv(conn, "ATTITUDE", 30)
        print(f"hanging at roll {math.degrees(att.roll):.1f} deg, pitch {math.degrees(att.pitch):.1f} deg; "
              f"ground contact {args.contact}")
        assert command(conn, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 4).result == 0
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == 0
        t0 = None
        onboard, physics = [], []
        n = 0
        while not onboard or onboard[-1][0] - t0 < args.seconds:
            m = recv(conn, ["LOCAL_POSITION_NED", "SIM_STATE", "STATUSTEXT"], 30)
            if m is None:
                break
            n += 1
            if n % 200 == 0:
                conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            if m.get_type() == "STATUSTEXT":
                print("STATUSTEXT", m.text)
            elif m.get_type() == "LOCAL_POSITION_NED":
                t = stamp_s(m)
                t0 = t if t0 is None else t0
                onboard.append((t, m.x, m.y, m.z))
            elif onboard:  # SIM_STATE carries no time stamp: the last LOCAL_POSITION_NED's
                physics.append((onboard[-1][0], *global_to_local_ned(home, m.lat_int * 1e-7, m.lon_int * 1e-7, m.alt)))
        conn.close()
    for name, rows in (("onboard (LOCAL_POSITION_NED)", onboard), ("physics (SIM_STATE)", physics)):
        a = np.array(rows)
        h = np.hypot(a[:, 1], a[:, 2])
        low = a[:, 3] > -0.05
        up = a[~low, 0]
        print(f"{name}: largest horizontal distance from home {h.max():.3f} m, within 5 cm of the ground "
              f"{(h[low].max() if low.any() else 0.0):.3f} m; at the end N {a[-1, 1]:+.2f} E {a[-1, 2]:+.2f} "
              f"D {a[-1, 3]:+.2f}; left the ground at "
              + (f"{up[0] - t0:.2f} s" if up.size else "never"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
