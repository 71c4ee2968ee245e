"""Fly the identification flight on a served rig from a pymavlink ground station that logs it, and identify.

    python -m gcs_tools.studies served-sysid [--rate-hz 100 500] [--speedup 20 2] [--chunk-ms 1.25 0.5] [--runs N]
    python -m gcs_tools.studies served-sysid --runs 3 --markdown docs/generated/served-sysid.md

A ``hilms`` rig with its centre of gravity moved to (-9, 7, 35) mm (the preset says (8, -8, 35) mm) is
served as ``rig-emulator serve`` in a subprocess. For each ``--rate-hz`` (with the ``--speedup`` and
``--chunk-ms`` at the same position) a pymavlink ground station asks for the rows the identification
needs (ATTITUDE, SERVO_OUTPUT_RAW, HILMS_LOAD_CELLS) at that rate with ``MAV_CMD_SET_MESSAGE_INTERVAL``,
keeps its own ``.tlog`` (``setup_logfile``), arms, starts the flight with ``MAV_CMD_HILMS_SYSID`` and logs
until ``sysid: done``; then ``rig-gcs identify --tlog`` reads the log. The table compares the delay, the
thrust gains and bias and the centre of gravity with the rig's, and gives the model check's verdict,
each as its range over ``--runs`` flights per rate.
``--markdown FILE`` writes the table as the page docs/how-to/identify.md includes.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from gcs_tools.studies.page import span
from protocol.dialect import mavlink as M
from rig_emulator.config.loader import load_config
from rig_emulator.testing.rig import RigProcess, command, connect, recv, stamp_s

COG = (-0.009, 0.007, 0.035)  # m: the rig's centre of gravity, away from the preset's
ROWS = (M.MAVLINK_MSG_ID_ATTITUDE, M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW, M.MAVLINK_MSG_ID_HILMS_LOAD_CELLS)
GUARD_S = 900.0  # wall-clock bound on one flight


def fly_and_identify(rate_hz: float, speedup: float, chunk_ms: float, workdir: Path) -> dict:
    """One served flight logged at ``rate_hz`` by the ground station, and its identification."""
    tlog = workdir / f"gcs-{rate_hz:g}hz.tlog"
    args = ["--set", f"joint.cog_offset={list(COG)}", "--chunk-ms", f"{chunk_ms:g}"]
    wall0 = time.monotonic()
    with RigProcess(speedup=speedup, args=args, airframe="hilms") as rig:
        conn = connect(rig.tcp_url)
        conn.setup_logfile(str(tlog), mode="wb")
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        if recv(conn, "HEARTBEAT", 30) is None:
            raise RuntimeError("no HEARTBEAT from the rig")
        for msg_id in ROWS:
            if command(conn, M.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / rate_hz).result != M.MAV_RESULT_ACCEPTED:
                raise RuntimeError(f"SET_MESSAGE_INTERVAL {msg_id} refused")
        if command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result != M.MAV_RESULT_ACCEPTED:
            raise RuntimeError("arming refused")
        if command(conn, M.MAV_CMD_HILMS_SYSID, 1).result != M.MAV_RESULT_ACCEPTED:
            raise RuntimeError("MAV_CMD_HILMS_SYSID refused")
        done = None
        t_last = None
        while done is None and time.monotonic() - wall0 < GUARD_S:
            m = conn.recv_match(blocking=True, timeout=0.5)
            if m is None:
                continue
            if m.get_type() == "ATTITUDE":
                t_last = stamp_s(m)
            elif m.get_type() == "STATUSTEXT":
                text = m.text if isinstance(m.text, str) else m.text.decode("ascii", "replace")
                if text.startswith(("sysid: done", "sysid: stopped")):
                    done = text
        if done is None or not done.startswith("sysid: done"):
            raise RuntimeError(f"the flight did not end: {done}")
        end = time.monotonic() + 5.0
        while time.monotonic() < end:  # one more simulated second of rows
            m = conn.recv_match(type="ATTITUDE", blocking=True, timeout=0.5)
            if m is not None and stamp_s(m) > t_last + 1.0:
                break
        conn.logfile.close()
        conn.close()
    flight_wall = time.monotonic() - wall0
    from gcs_tools.cli import main as gcs_main

    js = workdir / f"gcs-{rate_hz:g}hz.json"
    if gcs_main(["identify", "--tlog", str(tlog), "--json", str(js)]) != 0:
        raise RuntimeError("rig-gcs identify failed")
    doc = json.loads(js.read_text())
    est = {e["key"]: e for e in doc["estimates"]}
    return {"rate_hz": rate_hz, "speedup": speedup, "chunk_ms": chunk_ms, "flight_wall_s": flight_wall,
            "estimates": est, "findings": doc.get("findings") or []}


def _verdict(findings: list[dict]) -> str:
    """The model check in a table cell: silent, or the channels it flags with their largest residual."""
    if not findings:
        return "silent"
    worst: dict[str, float] = {}
    for f in findings:
        name = f.get("channel") or f.get("key") or "?"
        worst[name] = max(worst.get(name, 0.0), float(f.get("ratio", 0.0)))
    return "flags " + ", ".join(f"{k} ({v:.1f}x)" if v else k for k, v in sorted(worst.items()))


def table_rows(results: list[dict]) -> list[str]:
    """The Markdown table of ``results`` against the served rig's values: one row per rate, each figure's
    range over that rate's flights (a served rig's log differs from run to run: which chunk a message
    leaves in, and when the ground station arms, follow the wall clock)."""
    cfg = load_config("hilms", overrides={"joint.cog_offset": list(COG)})
    delay_ms = round(cfg["control.actuation_delay"] * 1000.0)  # the rig runs it in whole 1 ms steps
    gains, bias = cfg["motors.thrust_gain"], cfg["motors.thrust_bias_grf"]
    out = ["| ground station's log | served | flights | delay (rig: %d ms) | interval holds the delay "
           "| largest thrust gain error | thrust bias (rig: %g gr.F) | largest centre-of-gravity error "
           "| model check |" % (delay_ms, bias),
           "|---|---|---|---|---|---|---|---|---|"]
    for rate in dict.fromkeys(r["rate_hz"] for r in results):
        rs = [r for r in results if r["rate_hz"] == rate]
        e = [r["estimates"] for r in rs]
        delay = [x["control.actuation_delay"] for x in e]
        holds = sum(d["lo"] <= delay_ms / 1000.0 <= d["hi"] for d in delay)
        gerr = max(abs(x[f"motors.thrust_gain[{i}]"]["value"] - gains[i]) for x in e for i in range(4))
        cerr = max(abs(x[f"joint.cog_offset[{i}]"]["value"] - COG[i]) for x in e for i in range(3))
        flagged = [_verdict(r["findings"]) for r in rs if r["findings"]]
        check = f"silent on {len(rs) - len(flagged)} of {len(rs)}" + ("; " + "; ".join(flagged) if flagged else "")
        out.append(f"| {rate:g} Hz | {rs[0]['speedup']:g}x, `--chunk-ms {rs[0]['chunk_ms']:g}` | {len(rs)} "
                   f"| {span([d['value'] * 1e3 for d in delay], 1)} ms | {holds} of {len(rs)} | {gerr:.4f} "
                   f"| {span([x['motors.thrust_bias_grf']['value'] for x in e], 1)} gr.F | {cerr * 1e3:.2f} mm "
                   f"| {check} |")
    return out


def markdown_page(results: list[dict], command: str, machine: str) -> str:
    """The docs page: how the table was made, then the table."""
    walls = ", ".join(f"{min(w):.0f}-{max(w):.0f} s at {rate:g} Hz" for rate in dict.fromkeys(r["rate_hz"] for r in results)
                      for w in [[r["flight_wall_s"] for r in results if r["rate_hz"] == rate]])
    head = (f"Written by `{command}` on {machine}: the "
            f"identification flight served by `rig-emulator serve` (`hilms`, centre of gravity moved to "
            f"({COG[0] * 1e3:g}, {COG[1] * 1e3:g}, {COG[2] * 1e3:g}) mm), logged by a pymavlink ground station at each "
            f"rate and read by `rig-gcs identify --tlog` (flights of {walls} wall).")
    return "\n".join([head, ""] + table_rows(results)) + "\n"


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies served-sysid",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--rate-hz", type=float, nargs="+", default=[100.0, 500.0])
    ap.add_argument("--speedup", type=float, nargs="+", default=[20.0, 2.0])
    ap.add_argument("--chunk-ms", type=float, nargs="+", default=[1.25, 0.5])
    ap.add_argument("--runs", type=int, default=1, help="flights per rate (the table gives each figure's range)")
    ap.add_argument("--markdown", metavar="FILE", help="write the table as a docs page")
    return ap


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = parser()
    a = ap.parse_args(argv)
    if not len(a.rate_hz) == len(a.speedup) == len(a.chunk_ms):
        ap.error("--rate-hz, --speedup and --chunk-ms take one value per flight")
    with tempfile.TemporaryDirectory(prefix="served-sysid-") as d:
        results = [fly_and_identify(r, s, c, Path(d)) for _ in range(a.runs)
                   for r, s, c in zip(a.rate_hz, a.speedup, a.chunk_ms)]
    print("\n".join(table_rows(results)))
    if a.markdown:
        from gcs_tools.studies.page import command_line, machine

        command = command_line(["python -m gcs_tools.studies served-sysid", *argv])
        Path(a.markdown).write_text(markdown_page(results, command, machine()))
        print(f"wrote {a.markdown}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
