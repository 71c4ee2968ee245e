"""The figures of docs/how-to/offboard-and-fences.md, measured on a served rig over real sockets.

    python -m gcs_tools.studies px4-semantics [A] [B] [C] [D] [E] [--markdown FILE]   (default: all)

A  holds after a 60 s hover (take-off to 2.5 m, AUTO.LOITER): the jump of POSITION_TARGET_LOCAL_NED
   from the rig's LOCAL_POSITION_NED on DO_SET_MODE POSCTL and on the offboard-loss hold;
B  a set-point in AUTO.LOITER (does the mode change?) and DO_SET_MODE OFFBOARD 3 s after the last set-point;
C  FENCE_RADIUS 8, FENCE_ACTION hold, 40 s of SET_POSITION_TARGET_LOCAL_NED at 10 Hz towards N 20 m;
D  a mission item 50 km north at +2 m (GLOBAL_RELATIVE_ALT_INT): MISSION_ACK and the reason;
E  a refused mode (MANUAL) from one link: does a second link get the STATUSTEXT?

The rig runs in this process (RigThread) on the default plant `hilms` at SPEEDUP (environment,
default 10) x real time; every wait is on the rig's own time stamps. The rig is paced against the
wall clock, so figures vary by a few centimetres between runs.
"""

from __future__ import annotations

import argparse
import math
import os
import threading

from pymavlink import mavutil

from gcs_tools.studies.page import Page
from protocol.dialect import mavlink as M
from protocol.geodesy import local_enu_to_global
from protocol.mission_items import MissionItem
from rig_emulator.link.commands import modes as MD
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, recv_text

SPEEDUP = float(os.environ.get("SPEEDUP", "10"))
NAN = math.nan
POS_ONLY = 0b110111111000


def _heartbeats(conn, stop):
    while not stop.is_set():
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        stop.wait(1.0)


def _sim_t(conn):
    return recv(conn, "ATTITUDE", 10).time_boot_ms * 1e-3


def _wait_sim(conn, seconds, every=None, each=None):
    t0 = t = t_next = _sim_t(conn)
    while t - t0 < seconds:
        t = _sim_t(conn)
        if every and t >= t_next:
            each()
            t_next += every
    return t


def _mode(conn):
    hb = recv(conn, "HEARTBEAT", 10, lambda m: m.get_srcSystem() == 1)
    return MD.FlightModes.name_of(*MD.split_custom_mode(hb.custom_mode))


def _set_mode(conn, name):
    base, main, sub = mavutil.px4_map[name]
    return command(conn, M.MAV_CMD_DO_SET_MODE, base, main, sub).result


def _take_off(conn, rig, alt=2.5):
    assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
    ack = command(conn, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, NAN, NAN, NAN, rig.server.ctx.home.alt_m + alt)
    assert ack.result == M.MAV_RESULT_ACCEPTED
    assert recv_text(conn, lambda t: "takeoff complete" in t, timeout=300) is not None


def _target_and_position(conn):
    tgt = recv(conn, "POSITION_TARGET_LOCAL_NED", 10)
    pos = recv(conn, "LOCAL_POSITION_NED", 10, lambda m: m.time_boot_ms >= tgt.time_boot_ms)
    return (tgt.x, tgt.y, tgt.z), (pos.x, pos.y, pos.z)


def _fmt(v):
    return "N %.2f E %.2f D %.2f" % v


def _setpoint(conn, n, e, d):
    conn.mav.set_position_target_local_ned_send(0, 1, 1, M.MAV_FRAME_LOCAL_NED, POS_ONLY, n, e, d,
                                                0, 0, 0, 0, 0, 0, 0, 0)


def _session(overrides=None):
    rig = RigThread(speedup=SPEEDUP, airframe="hilms", overrides=overrides)
    conn = connect(rig.tcp_url)
    stop = threading.Event()
    threading.Thread(target=_heartbeats, args=(conn, stop), daemon=True).start()
    recv(conn, "ATTITUDE", 900)  # the step loop compiled (a cold numba cache takes minutes)
    return rig, conn, stop


def _close(rig, stop, *conns):
    stop.set()
    for c in conns:
        c.close()
    rig.stop()


def _row(out, figure, done, seen):
    out.print(f"{figure} {done}: {seen}", md=f"| {figure} | {done} | {seen} |")


def _offboard(conn, n, e, d):
    """A set-point, then DO_SET_MODE OFFBOARD (PX4's order); the result."""
    _setpoint(conn, n, e, d)
    return _set_mode(conn, "OFFBOARD")


def figure_a(out):
    for hold in ("POSCTL", "offboard loss"):
        rig, conn, stop = _session()
        _take_off(conn, rig)
        _wait_sim(conn, 60.0)
        if hold == "POSCTL":
            _set_mode(conn, "POSCTL")
        else:
            _, here = _target_and_position(conn)
            _offboard(conn, *here)
            recv_text(conn, lambda t: t.startswith("offboard set-points lost"), timeout=60)
        target, here = _target_and_position(conn)
        what = "DO_SET_MODE POSCTL" if hold == "POSCTL" else "OFFBOARD, then its set-points stop (the offboard-loss hold)"
        _row(out, "A", f"take-off to 2.5 m, 60 s hover in AUTO.LOITER, then {what}",
             f"POSITION_TARGET_LOCAL_NED {_fmt(target)}, LOCAL_POSITION_NED {_fmt(here)}: "
             f"{math.dist(target, here):.2f} m apart")
        _close(rig, stop, conn)


def figure_b(out):
    rig, conn, stop = _session()
    _take_off(conn, rig)
    _setpoint(conn, 0.0, 0.0, -2.5)
    _wait_sim(conn, 0.5)
    _row(out, "B", "a SET_POSITION_TARGET_LOCAL_NED in AUTO.LOITER", f"the mode stays {_mode(conn)}")
    _set_mode(conn, "LOITER")
    _wait_sim(conn, 3.0)
    result = _set_mode(conn, "OFFBOARD")
    _row(out, "B", "DO_SET_MODE OFFBOARD 3 s after the last set-point",
         f"{M.enums['MAV_RESULT'][result].name}, mode {_mode(conn)}")
    _close(rig, stop, conn)


def figure_c(out):
    rig, conn, stop = _session({"fence.radius": 8.0, "fence.action": "hold"})
    _take_off(conn, rig)
    entered = M.enums['MAV_RESULT'][_offboard(conn, 20.0, 0.0, -2.5)].name
    far, outside, t_last = 0.0, 0.0, None
    t0 = t_next = _sim_t(conn)
    t = t0
    while t - t0 < 40.0:
        m = recv(conn, ["ATTITUDE", "LOCAL_POSITION_NED"], 10)
        t = m.time_boot_ms * 1e-3
        if m.get_type() == "LOCAL_POSITION_NED":
            r = math.hypot(m.x, m.y)
            far = max(far, r)
            if r > 8.0 and t_last is not None:
                outside += t - t_last
            t_last = t
        elif t >= t_next:
            _setpoint(conn, 20.0, 0.0, -2.5)
            t_next += 0.1
    conn.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0, M.MAVLINK_MSG_ID_FENCE_STATUS, 0, 0, 0, 0, 0, 0)
    fs = recv(conn, "FENCE_STATUS", 10)
    _row(out, "C", "FENCE_RADIUS 8, FENCE_ACTION hold; a set-point towards N 20 m, DO_SET_MODE OFFBOARD, then "
                   "set-points towards N 20 m at 10 Hz for 40 s",
         f"OFFBOARD {entered}; farthest {far:.1f} m from home, {outside:.1f} s beyond 8 m, mode {_mode(conn)}, "
         f"FENCE_STATUS breach_status {fs.breach_status}, breach_count {fs.breach_count}, "
         f"breach_type {fs.breach_type}")
    _close(rig, stop, conn)


def figure_d(out):
    rig, conn, stop = _session()
    home = rig.server.ctx.home
    lat, lon, _ = local_enu_to_global(home, [0.0, 50_000.0, 0.0])
    item = MissionItem(seq=0, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, command=M.MAV_CMD_NAV_WAYPOINT, current=1,
                       x=lat, y=lon, z=2.0)
    result = MissionClient(conn).upload([item])
    text = recv_text(conn, lambda t: t.startswith("mission upload"), timeout=10)
    _row(out, "D", "a mission of one item 50 km north of home (the tangent plane's point) at +2 m, "
                   "GLOBAL_RELATIVE_ALT_INT", f"{M.enums['MAV_MISSION_RESULT'][result].name}: `{text and text[1]}`")
    _close(rig, stop, conn)


def figure_e(out):
    rig, conn, stop = _session()
    other = connect(rig.tcp_url, source_system=254)
    other.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    recv(other, "HEARTBEAT", 10)
    result = _set_mode(conn, "MANUAL")
    got = recv_text(other, lambda t: "MANUAL" in t, timeout=5)
    _row(out, "E", "DO_SET_MODE MANUAL from link 1, a second ground station on link 2",
         f"link 1: {M.enums['MAV_RESULT'][result].name}; link 2 got the STATUSTEXT `{got and got[1]}`")
    _close(rig, stop, conn, other)


FIGURES = {"A": figure_a, "B": figure_b, "C": figure_c, "D": figure_d, "E": figure_e}


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies px4-semantics",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("figures", nargs="*", metavar="FIGURE", type=str.upper,
                    help="which figures (default: all): A the holds' jump, B a set-point in a hold mode, C the fence "
                         "against a set-point stream, D a mission item beyond the fence, E a refused mode seen "
                         "from a second link")
    ap.add_argument("--markdown", metavar="FILE", help="also write the figures as a documentation page")
    return ap


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    unknown = [f for f in args.figures if f not in FIGURES]
    if unknown:
        ap.error(f"FIGURE {', '.join(unknown)}: must be among {' '.join(FIGURES)}")
    out = Page(args.markdown, f"The default plant `hilms` served in the process at {SPEEDUP:g}x real time "
                              "(SPEEDUP), flown over TCP by pymavlink; every wait is on the rig's own time stamps.")
    out.page("| figure | what the ground station did | what the rig did |")
    out.page("| --- | --- | --- |")
    for name in args.figures or FIGURES:
        FIGURES[name](out)
    out.write()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
