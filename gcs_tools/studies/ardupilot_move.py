"""ArduCopter SITL in lockstep with the rig (JSON interface): take-off, hover, a 5 m move and a
landing, per variant of the rig's parameter file.

Needs an ArduCopter SITL build made outside this repository (docs/how-to/flight-stacks.md,
"ArduPilot SITL"); ``--ardupilot DIR`` is its source tree, with ``build/sitl/bin/arducopter``.

    python -m gcs_tools.studies ardupilot-move --ardupilot ~/ardupilot --sessions 2 --markdown FILE

Each session starts a fresh rig (``rig-emulator serve --ardupilot-json``, ground link on TCP)
and a fresh ArduCopter (``-w``: parameters wiped, then ``copter.parm`` and the variant's file)
with the variant's parameters:

* ``shipped``: ``rig_emulator/link/ardupilot_json/hilms.parm`` as installed;
* ``move-default``: without its move limits (``WPNAV_ACCEL``, ``WPNAV_SPEED``: ArduCopter's);
* ``yaw-default``: without its yaw limits (``ATC_ACCEL_Y_MAX``, ``ATC_SLEW_YAW``);
* ``fitted``: with ArduCopter's thrust curve fitted to the rig (``MOT_SPIN_MIN 0.19``,
  ``MOT_SPIN_MAX 1.0``, ``MOT_THST_EXPO 0.5``, ``MOT_BAT_VOLT_MAX 0``) instead of its line.

A pymavlink client on ArduCopter's TCP 5760 waits for the EKF to use GPS, switches to GUIDED,
arms, takes off to 2 m (``MAV_CMD_NAV_TAKEOFF``), hovers 30 s, asks for 5 m north
(SET_POSITION_TARGET_LOCAL_NED) and after 30 s lands (LAND). Times are ArduCopter's
(``time_boot_ms``, simulated); the rig's SIM_STATE (its ground link) is paired with each of
ArduCopter's samples as the latest one received. The page gives each figure's range over the
sessions. ArduCopter uses fixed ports (5760, 9002): run one study at a time.
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from gcs_tools.studies.page import Page, span
from gcs_tools.studies.sitl import StackLink, chosen, free_port, git_commit, start_rig, stop, tilt_deg

#: the fitted thrust curve (docs/how-to/flight-stacks.md, "ArduCopter's thrust curve fitted to the rig")
FITTED = {"MOT_SPIN_MIN": 0.19, "MOT_SPIN_MAX": 1.0, "MOT_THST_EXPO": 0.5, "MOT_BAT_VOLT_MAX": 0.0}
YAW_LIMITS = ("ATC_ACCEL_Y_MAX", "ATC_SLEW_YAW")
MOVE_LIMITS = ("WPNAV_ACCEL", "WPNAV_SPEED")
#: variant -> (parameters set over the shipped file's, the file's parameters left out)
VARIANTS = {
    "shipped": ({}, ()),
    "move-default": ({}, MOVE_LIMITS),
    "yaw-default": ({}, YAW_LIMITS),
    "fitted": (FITTED, ()),
}
TAKEOFF_M = 2.0
MOVE_M = 5.0
HOVER_S = 30.0
MOVE_S = 30.0


def variant_parm(shipped: str, variant: str, extra: dict[str, float] | None = None) -> str:
    """The shipped parameter file with ``variant``'s changes and then ``extra`` (comments kept)."""
    changes, dropped = VARIANTS[variant]
    changes = {**changes, **(extra or {})}
    lines = []
    for line in shipped.splitlines():
        name = line.split("#", 1)[0].split()
        if name and (name[0] in dropped or name[0] in changes):
            continue
        lines.append(line)
    lines += [f"{k} {v:g}" for k, v in changes.items()]
    return "\n".join(lines) + "\n"


class Flight(StackLink):
    """ArduCopter's link and the rig's ground link, read in one loop."""

    ack_wait_s = 2.0

    def __init__(self, ap_url: str, rig_url: str):
        from pymavlink import mavutil

        self.M = mavutil.mavlink
        self.ap = None
        deadline = time.monotonic() + 60.0
        while self.ap is None:
            try:
                self.ap = mavutil.mavlink_connection(ap_url, source_system=255, retries=0)
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(1.0)
        self.link = self.ap
        self.rig = mavutil.mavlink_connection(rig_url, source_system=254)
        self.t = 0.0  # ArduCopter's time (s)
        self.att = self.lpos = self.rig_state = None
        self.armed = False
        self.texts: list[str] = []
        self.acks: dict = {}

    def pump(self, rows: list | None = None, timeout: float = 0.2):
        """Read what both links have; a row per GLOBAL_POSITION_INT into ``rows``. Returns the last message."""
        m = self.rig.recv_match(blocking=False)
        while m is not None:
            if m.get_type() == "SIM_STATE":
                self.rig_state = m
            m = self.rig.recv_match(blocking=False)
        msg = self.ap.recv_match(blocking=True, timeout=timeout)
        if msg is None or msg.get_srcSystem() != self.ap.target_system:
            return None
        ty = msg.get_type()
        if ty == "STATUSTEXT":
            self.texts.append(msg.text)
        elif ty == "ATTITUDE":
            self.att = msg
        elif ty == "LOCAL_POSITION_NED":
            self.lpos = msg
        elif ty == "HEARTBEAT":
            self.armed = bool(msg.base_mode & self.M.MAV_MODE_FLAG_SAFETY_ARMED)
        elif ty == "COMMAND_ACK":
            self.acks[msg.command] = msg.result
        elif ty == "GLOBAL_POSITION_INT":
            self.t = msg.time_boot_ms / 1000.0
            if rows is not None and self.att is not None and self.lpos is not None:
                r = self.rig_state
                rows.append((self.t, msg.relative_alt / 1000.0, self.att.roll, self.att.pitch, self.lpos.x,
                             self.lpos.y, r.alt if r else math.nan, r.roll if r else math.nan,
                             r.pitch if r else math.nan))
        return msg



def _say(text: str) -> None:
    print(f"  {text}", file=sys.stderr, flush=True)


def fly(f: Flight) -> dict:
    """EKF on GPS, GUIDED, arm, take off, hover, the 5 m move, land: the session's figures."""
    M = f.M
    f.ap.wait_heartbeat(timeout=120)
    f.target = (f.ap.target_system, f.ap.target_component)
    _say("heartbeat")
    # ArduCopter's own clock comes with GLOBAL_POSITION_INT: ask for it (and the rest) at 20 Hz first
    f.ap.mav.request_data_stream_send(f.ap.target_system, f.ap.target_component, M.MAV_DATA_STREAM_ALL, 10, 1)
    for msg_id in (30, 32, 33):  # ATTITUDE, LOCAL_POSITION_NED, GLOBAL_POSITION_INT
        f.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 50000, tries=2)
    if not f.wait(600.0, until=lambda: any("using GPS" in t for t in f.texts)):
        raise RuntimeError("ArduCopter's EKF did not use GPS in 600 s")
    _say(f"EKF on GPS at t = {f.t:.1f} s")
    ground: list = []
    f.wait(10.0, ground)
    rig_ground = sum(r[6] for r in ground[-20:]) / len(ground[-20:])
    f.ap.set_mode("GUIDED")
    f.wait(2.0)
    for _ in range(20):
        if f.command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1, tries=1) == 0:
            break
        f.wait(3.0)
    else:
        raise RuntimeError("ArduCopter refused to arm")
    _say(f"armed at t = {f.t:.1f} s")
    f.command(M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, TAKEOFF_M)
    f.wait(15.0)
    hover: list = []
    f.wait(HOVER_S, hover)
    x0, y0 = f.lpos.x, f.lpos.y
    alt0 = sum(r[1] for r in hover[-40:]) / len(hover[-40:])
    rig0 = sum(r[6] for r in hover[-40:]) / len(hover[-40:])
    z0 = -alt0
    f.ap.mav.set_position_target_local_ned_send(0, f.ap.target_system, f.ap.target_component, M.MAV_FRAME_LOCAL_NED,
                                                0b110111111000, x0 + MOVE_M, y0, z0, 0, 0, 0, 0, 0, 0, 0, 0)
    _say(f"move at t = {f.t:.1f} s")
    move: list = []
    f.wait(MOVE_S, move)
    f.ap.set_mode("LAND")
    landed = f.wait(120.0, until=lambda: not f.armed and f.t > 0)
    tx = x0 + MOVE_M
    arrive = next((r[0] - move[0][0] for r in move if abs(r[4] - tx) < 0.2 and abs(r[5] - y0) < 0.2), None)
    return {
        "hover_alt_m": [min(r[1] for r in hover), max(r[1] for r in hover)],
        "hover_rig_alt_m": [min(r[6] for r in hover) - rig_ground, max(r[6] for r in hover) - rig_ground],
        "hover_tilt_deg": max(tilt_deg(r[2], r[3]) for r in hover),
        "hover_xy_span_m": max(max(r[4] for r in hover) - min(r[4] for r in hover),
                               max(r[5] for r in hover) - min(r[5] for r in hover)),
        "move_alt_m": [min(r[1] for r in move), max(r[1] for r in move)],
        "move_alt_dev_m": max(abs(r[1] - alt0) for r in move),
        "move_rig_alt_dev_m": max(abs(r[6] - rig0) for r in move),
        "move_tilt_deg": max(tilt_deg(r[2], r[3]) for r in move),
        "move_rig_tilt_deg": max(tilt_deg(r[7], r[8]) for r in move),
        "arrive_s": arrive,
        "overshoot_m": max(r[4] for r in move) - tx,
        "landed": landed,
    }


def session(ardupilot: Path, variant: str, speedup: float, extra: dict[str, float] | None = None) -> dict:
    """One session: a fresh rig, a fresh ArduCopter with ``variant``'s parameters, the flight."""
    from rig_emulator.link.ardupilot_json import __file__ as package

    work = Path(tempfile.mkdtemp(prefix="ardupilot-"))
    parm = work / "rig.parm"
    parm.write_text(variant_parm((Path(package).parent / "hilms.parm").read_text(), variant, extra))
    rig_port = free_port()
    rig = start_rig(["--ardupilot-json", "--no-persist", "--sysid", "2", "--mavlink", f"tcpin:127.0.0.1:{rig_port}"],
                    "ardupilot json physics on")
    sitl = None
    try:
        defaults = f"{ardupilot / 'Tools' / 'autotest' / 'default_params' / 'copter.parm'},{parm}"
        with open(work / "sitl.log", "w") as console:
            sitl = subprocess.Popen([str(ardupilot / "build" / "sitl" / "bin" / "arducopter"), "--model",
                                     "JSON:127.0.0.1", "--speedup", f"{speedup:g}", "-I0", "-w", "--defaults",
                                     defaults, "--home", "35.7,51.4,1200,0"], cwd=work, stdout=console,
                                    stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        result = fly(Flight("tcp:127.0.0.1:5760", f"tcp:127.0.0.1:{rig_port}"))
    finally:
        stop(sitl, signal.SIGKILL, 10.0)
        stop(rig, signal.SIGINT, 60.0)
        shutil.rmtree(work, ignore_errors=True)
    result.update(lockstep(rig.lines))
    return result


def lockstep(lines: list[str]) -> dict:
    """What the rig printed of the session: frames stepped, repeated and missed, messages dropped."""
    out = {"frames": None, "repeated": None, "missed": None, "dropped": None}
    for line in lines:
        m = re.search(r"after (\d+) frames \((\d+) repeated, (\d+) missed\)", line)
        if m:
            out.update(frames=int(m[1]), repeated=int(m[2]), missed=int(m[3]))
        m = re.search(r"dropped (\{.*\})", line)
        if m:
            out["dropped"] = m[1]
    return out


#: the page's columns after the variant's
COLUMNS = ("hover altitude (the rig's)", "hover tilt, x/y span", "move altitude (the rig's deviation)",
           "move tilt (the rig's)", "within 0.2 m after, overshoot", "landed and disarmed",
           "frames in lockstep (repeated, missed), messages dropped")


def row(variant: str, sessions: list[dict]) -> str:
    """One variant's row of the page: each figure's range over ``sessions``."""
    def rng(key, digits):
        vals = []
        for s in sessions:
            v = s[key]
            if v is None:
                continue
            vals += list(v) if isinstance(v, list) else [v]
        return span(vals, digits) if vals else "-"

    cells = [
        f"{rng('hover_alt_m', 3)} m ({rng('hover_rig_alt_m', 3)} m)",
        f"<= {max(s['hover_tilt_deg'] for s in sessions):.1f} deg, {rng('hover_xy_span_m', 2)} m",
        f"{rng('move_alt_m', 2)} m ({rng('move_rig_alt_dev_m', 2)} m)",
        f"{rng('move_tilt_deg', 1)} deg ({rng('move_rig_tilt_deg', 1)} deg)",
        f"{rng('arrive_s', 2)} s, {rng('overshoot_m', 2)} m",
        f"{sum(bool(s['landed']) for s in sessions)} of {len(sessions)}",
        f"{rng('frames', 0)} ({rng('repeated', 0)}, {rng('missed', 0)}), "
        f"{', '.join(sorted({str(s['dropped']) for s in sessions}))}",
    ]
    return f"| `{variant}` | {' | '.join(cells)} |"


def describe(variant: str, extra: dict[str, float] | None = None) -> str:
    """What ``variant`` (and ``extra``) changes of the shipped file, in words."""
    changes, dropped = VARIANTS[variant]
    changes = {**changes, **(extra or {})}
    parts = []
    if changes:
        parts.append("with " + ", ".join(f"`{k} {v:g}`" for k, v in changes.items()))
    if dropped:
        parts.append("without " + ", ".join(f"`{k}`" for k in dropped) + " (ArduCopter's defaults)")
    return "`hilms.parm` " + ("; ".join(parts) if parts else "as shipped")


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies ardupilot-move", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ardupilot", required=True, metavar="DIR",
                    help="ArduPilot's source tree, built for SITL (build/sitl/bin/arducopter)")
    ap.add_argument("--sessions", type=int, default=2, metavar="N", help="sessions per variant (default %(default)s)")
    ap.add_argument("--variants", default=",".join(VARIANTS), metavar="A,B",
                    help=f"variants to fly, of {', '.join(VARIANTS)} (default all)")
    ap.add_argument("--speedup", type=float, default=1.0,
                    help="ArduCopter's --speedup (default %(default)g; lockstep keeps the flight the same)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="set an ArduCopter parameter in every variant flown (repeatable): try a change")
    ap.add_argument("--markdown", metavar="FILE", help="also write the table to FILE, with the command and the machine")
    return ap


def _extra(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            if not sep or not name.strip():
                raise ValueError
            out[name.strip().upper()] = float(value)
        except ValueError:
            raise ValueError(f"--set {item!r}: must be NAME=NUMBER (an ArduCopter parameter)") from None
    return out


def main(argv=None) -> None:
    a = parser().parse_args(sys.argv[1:] if argv is None else argv)
    ardupilot = Path(a.ardupilot).expanduser().resolve()
    names = chosen(a.variants, VARIANTS, "--variants", parser().error)
    if a.sessions < 1:
        parser().error("--sessions: must be at least 1")
    if not (a.speedup > 0):
        parser().error("--speedup: must be positive")
    try:
        extra = _extra(a.set)
    except ValueError as exc:
        parser().error(str(exc))
    binary = ardupilot / "build" / "sitl" / "bin" / "arducopter"
    if not binary.is_file():
        parser().error(f"--ardupilot: {binary} does not exist: build ArduCopter SITL first "
                       "(docs/how-to/flight-stacks.md)")
    commit = git_commit(ardupilot)
    out = Page(a.markdown, f"ArduCopter SITL (commit {commit}, `--speedup {a.speedup:g}`) flying the default rig "
                           f"`hilms` in lockstep: each figure the range over {a.sessions} session(s) per variant "
                           "(a fresh rig and ArduCopter each); ArduCopter's figures, the rig's SIM_STATE in brackets.")
    for n in names:
        out.print(f"* `{n}`: {describe(n, extra)}")
    out.blank()
    out.print(f"| variant | {' | '.join(COLUMNS)} |")
    out.print("|---|" + "---|" * len(COLUMNS))
    for n in names:
        sessions = []
        for i in range(a.sessions):
            r = session(ardupilot, n, a.speedup, extra)
            sessions.append(r)
            print(f"{n} session {i + 1}: move altitude {r['move_alt_m'][0]:.2f}-{r['move_alt_m'][1]:.2f} m, "
                  f"tilt {r['move_tilt_deg']:.1f} deg, landed {r['landed']}", file=sys.stderr, flush=True)
        out.print(row(n, sessions))
    out.write()


if __name__ == "__main__":
    main()
