"""PX4 SITL in lockstep with the rig: take-off, hover and three 5 m repositions, per PX4 airframe.

Needs a PX4 SITL build made outside this repository (docs/how-to/flight-stacks.md, "Build PX4
SITL"); ``--px4 DIR`` is its source tree, with ``build/px4_sitl_default`` in it.

    python -m gcs_tools.studies px4-reposition --px4 ~/px4 --sessions 3 --markdown FILE

Each session starts a fresh rig (``rig-emulator serve --px4-simulator``, ground link on TCP) and
a fresh PX4 (a new ``rootfs``) with one airframe:

* ``hilms``: the rig's airframe ``10090_none_hilms`` (geometry and tuning), installed into the
  build as the guide says;
* ``geometry``: the same geometry on PX4's multicopter defaults, ``THR_MDL_FAC 0`` and
  ``MPC_THR_HOVER 0.78`` (linear motors at the ideal plant's hover share), written into the build
  as ``10091_none_hilmsgeom``;
* each ``--variant NAME=VALUE[,...]``: the rig's airframe with those values changed, written into the
  build as ``10092_none_hilmsv0``, ``10093_none_hilmsv1``, ... (a column each).

A pymavlink client on PX4's offboard link (UDP 14540) arms once PX4 has a home position, takes
off (``MAV_CMD_NAV_TAKEOFF``, PX4's 2.5 m), hovers 20 s and sends three ``MAV_CMD_DO_REPOSITION``
(5 m north, then 5 m east, then 3 m south and 4 m west; yaw NaN: PX4 faces the target) 30 s of
simulated time apart, then lands. Over each 30 s: the largest ``|z - z_hold|`` and tilt
``acos(cos roll cos pitch)`` from PX4's LOCAL_POSITION_NED and ATTITUDE and from the rig's
SIM_STATE (its ground link, stamped with the rig's simulated time), the largest heading change,
the time to within 0.3 m of the target and the error at the end. The page gives each figure's
range over all sessions and repositions. PX4 uses fixed ports (4560, 14540): run one study at a
time, with no other PX4 on the machine.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from gcs_tools.studies.page import Page, span
from gcs_tools.studies.sitl import StackLink, chosen, free_port, git_commit, start_rig, stop, tilt_deg, wrap

NAN = float("nan")
#: the shipped airframe, PX4's name for it, and the geometry-only variant written beside it
AIRFRAMES = {"hilms": ("10090_none_hilms", "none_hilms"), "geometry": ("10091_none_hilmsgeom", "none_hilmsgeom")}
#: the repositions: (north, east) m from where the rig hovers before each
TARGETS = ((5.0, 0.0), (0.0, 5.0), (-3.0, -4.0))
HOVER_S = 20.0
SETTLE_S = 30.0
#: the figures per reposition, in the page's order: key -> (row label, unit, digits)
FIGURES = {
    "alt_dev_m": ("altitude deviation, PX4's estimate", "m", 3),
    "rig_alt_dev_m": ("altitude deviation, the rig's SIM_STATE", "m", 3),
    "tilt_deg": ("largest tilt, PX4's estimate", "deg", 1),
    "rig_tilt_deg": ("largest tilt, the rig's SIM_STATE", "deg", 1),
    "yaw_dev_deg": ("largest heading change (about 90 deg asked in the first two, 143 deg in the third)", "deg", 0),
    "arrive_s": ("time to within 0.3 m of the target", "s", 1),
    "end_err_m": ("position error 30 s after the command", "m", 3),
}


def geometry_airframe(shipped: str) -> str:
    """The shipped airframe's geometry lines on PX4's defaults, with linear motors at 0.78 hover."""
    keep = [line for line in shipped.splitlines()
            if line.startswith(". ") or line.startswith("param set-default CA_")
            or line.startswith("param set-default PWM_MAIN_FUNC")]
    return "\n".join(["#!/bin/sh", "# the HILMS rig's geometry only (gcs_tools.studies px4-reposition)", *keep,
                      "param set-default THR_MDL_FAC 0.0", "param set-default MPC_THR_HOVER 0.78", ""])


def variant_airframe(shipped: str, changes: dict[str, str]) -> str:
    """The shipped airframe with ``changes`` (PX4 parameter -> value) set after its own lines (PX4 keeps the
    last ``param set-default`` of a name)."""
    lines = [f"param set-default {k} {v}" for k, v in changes.items()]
    return shipped.rstrip("\n") + "\n\n# changed by gcs_tools.studies px4-reposition --variant\n" + "\n".join(lines) + "\n"


def variant_names(i: int) -> tuple[str, str]:
    """(file, PX4_SIM_MODEL) of the i-th --variant (0-based): 10092_none_hilmsv0, ..."""
    return f"{10092 + i}_none_hilmsv{i}", f"none_hilmsv{i}"


def parse_variant(text: str) -> dict[str, str]:
    """``NAME=VALUE[,NAME=VALUE...]`` of ``--variant`` (PX4 parameter names, numbers)."""
    out = {}
    for item in text.split(","):
        name, sep, value = item.partition("=")
        name = name.strip().upper()
        try:
            if not sep or not name or not name.replace("_", "").isalnum():
                raise ValueError
            float(value)
        except ValueError:
            raise ValueError(f"--variant {text!r}: must be NAME=NUMBER[,NAME=NUMBER...] (PX4 parameters)") from None
        out[name] = value.strip()
    return out


def install_airframes(build: Path, variants: list[dict[str, str]] = ()) -> None:
    """Copy the rig's airframe into the build and write the geometry-only one and each variant beside it."""
    from rig_emulator.link.px4_simulator.serve_px4 import AIRFRAME_FILE

    folder = build / "etc" / "init.d-posix" / "airframes"
    if not folder.is_dir():
        raise SystemExit(f"--px4: {folder} does not exist: build PX4 SITL first (docs/how-to/flight-stacks.md)")
    shipped = Path(AIRFRAME_FILE).read_text()
    (folder / AIRFRAMES["hilms"][0]).write_text(shipped)
    (folder / AIRFRAMES["geometry"][0]).write_text(geometry_airframe(shipped))
    for i, changes in enumerate(variants):
        (folder / variant_names(i)[0]).write_text(variant_airframe(shipped, changes))






class Flight(StackLink):
    """PX4's offboard link and the rig's ground link, read in one loop; times are simulated."""

    target = (1, 1)

    def __init__(self, px4_url: str, rig_url: str):
        from pymavlink import mavutil

        self.M = mavutil.mavlink
        self.px4 = mavutil.mavlink_connection(px4_url, source_system=255, source_component=190)
        self.link = self.px4
        self.rig = mavutil.mavlink_connection(rig_url, source_system=254, source_component=190)
        self.lpos: list[tuple] = []  # PX4: (t, x, y, z) NED
        self.att: list[tuple] = []  # PX4: (t, roll, pitch, yaw)
        self.rig_rows: list[tuple] = []  # rig: (t, alt, roll, pitch)
        self.t = 0.0  # PX4's time (s)
        self.rig_t = 0.0  # the rig's time (s)
        self.gpos = self.home = None
        self.armed = False
        self.acks: dict = {}

    def pump(self, rows: list | None = None, timeout: float = 0.05) -> None:
        """Read what both links have (PX4's samples go to ``lpos`` and ``att``; ``rows`` is not used)."""
        m = self.px4.recv_match(blocking=True, timeout=timeout)
        while m is not None:
            self._px4(m)
            m = self.px4.recv_match(blocking=False)
        m = self.rig.recv_match(blocking=False)
        while m is not None:
            ty = m.get_type()
            if ty in ("ATTITUDE", "LOCAL_POSITION_NED", "SYSTEM_TIME"):
                self.rig_t = m.time_boot_ms / 1000.0
            elif ty == "SIM_STATE":
                self.rig_rows.append((self.rig_t, m.alt, m.roll, m.pitch))
            m = self.rig.recv_match(blocking=False)

    def _px4(self, m) -> None:
        if m.get_srcSystem() != 1 or m.get_srcComponent() != 1:
            return
        ty = m.get_type()
        if ty == "LOCAL_POSITION_NED":
            self.t = m.time_boot_ms / 1000.0
            self.lpos.append((self.t, m.x, m.y, m.z))
        elif ty == "ATTITUDE":
            self.t = m.time_boot_ms / 1000.0
            self.att.append((self.t, m.roll, m.pitch, m.yaw))
        elif ty == "GLOBAL_POSITION_INT":
            self.gpos = m
        elif ty == "HOME_POSITION":
            self.home = m
        elif ty == "HEARTBEAT":
            self.armed = bool(m.base_mode & self.M.MAV_MODE_FLAG_SAFETY_ARMED)
        elif ty == "COMMAND_ACK":
            self.acks[m.command] = m.result

    def reposition(self, lat: float, lon: float):
        """MAV_CMD_DO_REPOSITION (COMMAND_INT, global) to ``lat``, ``lon`` at the current altitude: the result."""
        M = self.M
        return self.acked(M.MAV_CMD_DO_REPOSITION, lambda: self.px4.mav.command_int_send(
            *self.target, M.MAV_FRAME_GLOBAL, M.MAV_CMD_DO_REPOSITION, 0, 0, -1, 1, 0, NAN,
            int(round(lat * 1e7)), int(round(lon * 1e7)), NAN), tries=5)


def fly(flight: Flight) -> dict:
    """Arm, take off, hover, the three repositions, land: the session's figures."""
    M = flight.M
    flight.px4.wait_heartbeat(timeout=120)
    for msg_id, us in ((32, 20000), (30, 10000), (33, 100000), (242, 1000000)):
        flight.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, us, tries=2)
    w0 = time.monotonic()
    while flight.home is None or flight.gpos is None or not flight.lpos:
        flight.pump()
        if time.monotonic() - w0 > 300:
            raise RuntimeError("PX4 gave no home position in 300 s")
        if flight.home is None and int(time.monotonic() - w0) % 3 == 0:
            flight.command(M.MAV_CMD_REQUEST_MESSAGE, 242, tries=1)
    for _ in range(120):
        if flight.command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1) == 0:
            break
        flight.wait(1.0)
    else:
        raise RuntimeError("PX4 refused to arm for 120 s")
    flight.command(M.MAV_CMD_NAV_TAKEOFF, -1, 0, 0, NAN, NAN, NAN, NAN)
    flight.wait(15.0 + HOVER_S)
    th = flight.t
    hz = [-z for (t, x, y, z) in flight.lpos if th - 10.0 <= t <= th]
    ht = [tilt_deg(r, p) for (t, r, p, _) in flight.att if th - 10.0 <= t <= th]
    result = {"hover_alt_m": (min(hz), max(hz)), "hover_tilt_deg": max(ht), "repositions": []}
    for dn, de in TARGETS:
        pre = [(x, y, z) for (t, x, y, z) in flight.lpos if flight.t - 5.0 <= t <= flight.t]
        x0, y0, z0 = (sum(p[i] for p in pre) / len(pre) for i in range(3))
        rig_pre = [a for (t, a, _, _) in flight.rig_rows if flight.rig_t - 5.0 <= t <= flight.rig_t]
        yaw0 = flight.att[-1][3]
        g = flight.gpos
        lat0, lon0 = g.lat / 1e7, g.lon / 1e7
        xn, ye = flight.lpos[-1][1], flight.lpos[-1][2]  # the offsets are from PX4's current estimate
        lat = lat0 + math.degrees((x0 + dn - xn) / 6378137.0)
        lon = lon0 + math.degrees((y0 + de - ye) / (6378137.0 * math.cos(math.radians(lat0))))
        t0, rt0 = flight.t, flight.rig_t
        if flight.reposition(lat, lon) != 0:
            raise RuntimeError("PX4 did not accept MAV_CMD_DO_REPOSITION")
        flight.wait(SETTLE_S)
        t1, rt1 = flight.t, flight.rig_t
        lp = [row for row in flight.lpos if t0 <= row[0] <= t1]
        at = [row for row in flight.att if t0 <= row[0] <= t1]
        rig = [row for row in flight.rig_rows if rt0 <= row[0] <= rt1]
        end = lp[-1]
        st = {"alt_dev_m": max(abs(z - z0) for (_, _, _, z) in lp),
              "tilt_deg": max(tilt_deg(r, p) for (_, r, p, _) in at),
              "yaw_dev_deg": max(abs(math.degrees(wrap(y - yaw0))) for (_, _, _, y) in at),
              "arrive_s": next((t - t0 for (t, x, y, _) in lp if math.hypot(x - x0 - dn, y - y0 - de) < 0.3), None),
              "end_err_m": math.hypot(end[1] - (x0 + dn), end[2] - (y0 + de))}
        if rig and rig_pre:
            a0 = sum(rig_pre) / len(rig_pre)
            st["rig_alt_dev_m"] = max(abs(a - a0) for (_, a, _, _) in rig)
            st["rig_tilt_deg"] = max(tilt_deg(r, p) for (_, _, r, p) in rig)
        result["repositions"].append(st)
    flight.command(M.MAV_CMD_NAV_LAND, 0, 0, 0, NAN, NAN, NAN, NAN)
    result["landed"] = flight.wait(60.0, until=lambda: not flight.armed)
    return result






def session(px4: Path, model: str, seed: int | None) -> dict:
    """One session: a fresh rig, a fresh PX4 with the airframe PX4_SIM_MODEL ``model``, the flight."""
    build = px4 / "build" / "px4_sitl_default"
    rig_port = free_port()
    args = ["--px4-simulator", "127.0.0.1:4560", "--mavlink", f"tcpin:127.0.0.1:{rig_port}", "--no-persist"]
    rig = start_rig(args + (["--set", f"sim.seed={seed}"] if seed is not None else []), "px4 simulator on")
    rootfs = Path(tempfile.mkdtemp(prefix="px4-rootfs-"))
    px4_proc = None
    try:
        env = dict(os.environ, PX4_SIM_MODEL=model)
        env.pop("PX4_SYS_AUTOSTART", None)
        with open(rootfs / "console.log", "w") as console:
            px4_proc = subprocess.Popen([str(build / "bin" / "px4"), "-d", str(build / "etc")], cwd=rootfs, env=env,
                                        stdout=console, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        return fly(Flight("udpin:127.0.0.1:14540", f"tcp:127.0.0.1:{rig_port}"))
    finally:
        stop(px4_proc, seconds=10.0)
        stop(rig, signal.SIGINT)
        shutil.rmtree(rootfs, ignore_errors=True)


def table(results: dict[str, list[dict]]) -> list[str]:
    """The page's table: one column per airframe (``results``' keys are the headers), each cell the range
    over sessions and repositions."""
    names = list(results)
    rows = [f"| 5 m reposition | {' | '.join(names)} |",
            "|---|" + "---|" * len(names)]
    for key, (label, unit, digits) in FIGURES.items():
        cells = []
        for n in names:
            vals = [r[key] for s in results[n] for r in s["repositions"] if r.get(key) is not None]
            cells.append(f"{span(vals, digits)} {unit}" if vals else "-")
        rows.append(f"| {label} | {' | '.join(cells)} |")
    cells = []
    for n in names:
        lo = min(s["hover_alt_m"][0] for s in results[n])
        hi = max(s["hover_alt_m"][1] for s in results[n])
        cells.append(f"{lo:.2f}-{hi:.2f} m, tilt within {max(s['hover_tilt_deg'] for s in results[n]):.1f} deg")
    rows.append(f"| hover before, PX4's estimate | {' | '.join(cells)} |")
    cells = [f"{sum(bool(s['landed']) for s in results[n])} of {len(results[n])}" for n in names]
    rows.append(f"| sessions landed and disarmed | {' | '.join(cells)} |")
    return rows


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies px4-reposition", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--px4", required=True, metavar="DIR", help="PX4's source tree, built for SITL (build/px4_sitl_default)")
    ap.add_argument("--sessions", type=int, default=3, metavar="N", help="sessions per airframe (default %(default)s)")
    ap.add_argument("--airframes", default="geometry,hilms", metavar="A,B",
                    help=f"airframes to fly, of {', '.join(AIRFRAMES)} (default %(default)s)")
    ap.add_argument("--variant", action="append", default=[], metavar="NAME=VALUE[,...]",
                    help="also fly the rig's airframe with these PX4 parameters changed (repeatable: one column "
                         "each); what a row of the guide's parameter table does")
    ap.add_argument("--seed", type=int, default=None, help="the rig's noise seed (sim.seed; default the preset's)")
    ap.add_argument("--markdown", metavar="FILE", help="also write the table to FILE, with the command and the machine")
    return ap


def main(argv=None) -> None:
    a = parser().parse_args(sys.argv[1:] if argv is None else argv)
    px4 = Path(a.px4).expanduser().resolve()
    names = chosen(a.airframes, AIRFRAMES, "--airframes", parser().error)
    if a.sessions < 1:
        parser().error("--sessions: must be at least 1")
    try:
        variants = [parse_variant(v) for v in a.variant]
    except ValueError as exc:
        parser().error(str(exc))
    if len(variants) > 8:
        parser().error("--variant: at most 8 (airframes 10092..10099)")
    binary = px4 / "build" / "px4_sitl_default" / "bin" / "px4"
    if not binary.is_file():
        parser().error(f"--px4: {binary} does not exist: build PX4 SITL first (docs/how-to/flight-stacks.md)")
    install_airframes(px4 / "build" / "px4_sitl_default", variants)
    commit = git_commit(px4)
    out = Page(a.markdown, f"PX4 SITL (commit {commit}) flying the default rig `hilms` in lockstep: each figure "
                           f"the range over {a.sessions} session(s) per airframe (a fresh rig and PX4 each) of "
                           f"{len(TARGETS)} repositions each.")
    columns = [(f"`{AIRFRAMES[n][0]}`", AIRFRAMES[n][1]) for n in names]
    columns += [(f"`{AIRFRAMES['hilms'][0]}` with " + ", ".join(f"`{k} {v}`" for k, v in changes.items()),
                 variant_names(i)[1]) for i, changes in enumerate(variants)]
    results: dict[str, list[dict]] = {header: [] for header, _ in columns}
    for i in range(a.sessions):
        for header, model in columns:
            r = session(px4, model, a.seed)
            results[header].append(r)
            reps = " ".join(f"{x['alt_dev_m']:.3f}/{x.get('rig_alt_dev_m', NAN):.3f} m "
                            f"{x['tilt_deg']:.1f}/{x.get('rig_tilt_deg', NAN):.1f} deg" for x in r["repositions"])
            print(f"{model} session {i + 1}: {reps}; landed {r['landed']}", flush=True)
    for line in table(results):
        out.print(line)
    out.write()


if __name__ == "__main__":
    main()
