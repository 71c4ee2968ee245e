"""``rig-gcs``: ground tools for the HILMS rig (or any MAVLink vehicle) without a ground station.

Commands (``rig-gcs COMMAND --help`` for each):

* ``mission upload|download|clear CONNECTION [FILE]`` - mission transfer, .plan / QGC WPL 110
  files or the paper's missions (``--rectangle WxH``, ``--helix``); ``mission make FILE``
  writes a generated mission to a file.
* ``fly CONNECTION [FILE]`` - ground-driven waypoint flight with the 8 cm switching of Sec. 4-4.
* ``log CONNECTION -o run.tlog`` - record telemetry (.tlog, optional CSV of chosen fields).
* ``errors run.tlog`` - the mean errors of Eq. 45 in the layout of Table 6.
* ``plot run.tlog -o DIR`` - PNG plots (attitude, XY path with the switching circles, XYZ,
  3D path, errors against time, thrusts, load cells), titled with the run's scenario,
  strategy, airframe and seed.
* ``csv run.tlog --csv out.csv --fields ...`` - export chosen fields of a .tlog.
* ``param list|get|set|save|load CONNECTION ...`` - the vehicle's parameters; QGroundControl
  ``.params`` and MAVProxy ``NAME VALUE`` files (:mod:`gcs_tools.param_cli`).
* ``stability [--json]`` - stability analysis of the FLC gains (Eq. 16-32): fitted planes, the LMI
  of Eq. 32, the bound R2 of Eq. 31 (exit 1 when the LMI is infeasible; needs the ``analysis`` extra).
* ``reproduce -o DIR`` - the paper's experiments, our figures and numbers next to the paper's, a
  verdict on each claim (:mod:`gcs_tools.reproduce`, docs/explanation/readings.md).
* ``identify --params KEY=LO:HI,... --paper | --tlog run.tlog --scenario NAME -o fit.toml`` - fit
  parameters of the emulated rig to the paper's numbers or to flight logs, written as a preset
  (:mod:`gcs_tools.identify`, docs/how-to/identify.md).

CONNECTION is a pymavlink connection string: ``tcp:127.0.0.1:5760``, ``udpin:0.0.0.0:14550``, ...

Exit codes: 0 success, 1 the operation failed (link, timeout, rejected, nothing computable),
2 bad usage or input (nothing was sent).
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
from pathlib import Path

from gcs_tools.arg_types import finite_number as _number
from gcs_tools.arg_types import positive_number as _positive
from gcs_tools.errors import EXIT_OK, EXIT_USAGE, GcsError, OperationError, UsageError

# Heavy modules (numpy, the MAVLink dialect, matplotlib, numba, scipy, the rig emulator) are
# imported inside the commands that need them: `rig-gcs --help` and `rig-gcs errors` start fast.

DEFAULT_HOME_TEXT = "35.7,51.4,1200"  # rig-emulator serve's default --home (rig_emulator/link/serve_args.py)

PROG = "rig-gcs"


def _size(text: str) -> tuple[float, float]:
    parts = text.lower().split("x")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"{text!r}: expected WIDTHxHEIGHT in metres, e.g. 5x3")
    return _positive(parts[0]), _positive(parts[1])


def _home(text: str):
    from protocol.geodesy import Home

    parts = text.split(",")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(f"{text!r}: expected LAT,LON,ALT")
    try:
        return Home(*(float(p) for p in parts))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _rate(text: str) -> tuple[str, float]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"{text!r}: expected MESSAGE=HZ, e.g. ATTITUDE=50")
    name, hz = text.split("=", 1)
    return name.strip().upper(), _number(hz)


# --- missions -------------------------------------------------------------------------------------------------

def _add_generator_args(p) -> None:
    g = p.add_argument_group("built-in missions (instead of FILE)")
    g.add_argument("--rectangle", type=_size, metavar="WxH", help="the Sec. 4-4 rectangle, W m east by H m north")
    g.add_argument("--helix", action="store_true", help="the line-then-helix of Eq. 46 as waypoints")
    g.add_argument("--altitude", type=_number, default=2.0, help="rectangle altitude Z (m, up): %(default)s")
    g.add_argument("--spacing", type=_positive, default=0.5, help="helix waypoint spacing along the path (m): %(default)s")
    g.add_argument("--t-end", type=_positive, default=60.0, help="helix end time of Eq. 46 (s): %(default)s")
    g.add_argument("--radius", type=_positive, default=0.08, help="switching (acceptance) radius (m): %(default)s")
    g.add_argument("--frame", choices=("global", "local"), default="global",
                   help="write items in MAV_FRAME_GLOBAL_RELATIVE_ALT about --home (default: every ground station "
                        "reads them alike) or MAV_FRAME_LOCAL_NED (MAVProxy's wp load scales local x/y by 1e7, the "
                        "MAVLink spec and the rig by 1e4)")
    g.add_argument("--home", type=_home, metavar="LAT,LON,ALT",
                   help="home for --frame global (default: the vehicle's HOME_POSITION; for mission make, the home "
                        "rig-emulator serve uses by default, %s)" % DEFAULT_HOME_TEXT)


def _generated(args, home=None):
    from gcs_tools.missions import helix_points, mission_from_enu, rectangle_points

    if args.rectangle and args.helix:
        raise UsageError("give either --rectangle or --helix, not both")
    if args.rectangle:
        pts = rectangle_points(args.rectangle[0], args.rectangle[1], args.altitude)
    elif args.helix:
        pts = helix_points(args.spacing, args.t_end)
    else:
        return None
    return mission_from_enu(pts, args.radius, args.frame, args.home or home)


def _mission_source(args, link=None):
    """The mission of FILE or of a generator (UsageError for neither/both)."""
    from protocol.mission_files import load_mission

    generated = args.rectangle or args.helix
    if args.file and generated:
        raise UsageError("give a mission FILE or a built-in mission (--rectangle/--helix), not both")
    if args.file:
        return load_mission(args.file)
    if not generated:
        raise UsageError("no mission: give a FILE (.plan, .waypoints, .txt) or --rectangle WxH / --helix")
    home = None
    if args.frame == "global" and args.home is None:
        if link is None:
            raise UsageError("--frame global needs --home LAT,LON,ALT")
        home = _vehicle_home(link)
    return _generated(args, home)


def _vehicle_home(link):
    from protocol.geodesy import Home

    hp = link.home_position()
    if hp is None:
        raise OperationError("the vehicle sent no HOME_POSITION")
    return Home(hp.latitude * 1e-7, hp.longitude * 1e-7, hp.altitude * 1e-3)


def _open_link(args):
    from gcs_tools.link import open_link

    return open_link(args)


def cmd_mission(args) -> int:
    from gcs_tools import mission_client
    from protocol.mission_files import file_format, save_mission

    if args.action == "make":
        if not args.file:
            raise UsageError("mission make needs the FILE to write")
        file_format(args.file)
        default_home = _home(DEFAULT_HOME_TEXT) if args.frame == "global" and args.home is None else None
        mission = _generated(args, default_home)
        if mission is None:
            raise UsageError("mission make needs --rectangle WxH or --helix")
        save_mission(mission, args.file)
        print(f"wrote {len(mission.items)} items to {args.file}")
        return EXIT_OK
    if args.action == "upload":
        needs_home_from_link = (not args.file and (args.rectangle or args.helix) and args.frame == "global"
                            and args.home is None)
        mission = None if needs_home_from_link else _mission_source(args)  # checked before connecting
        with _open_link(args) as link:
            if mission is None:
                mission = _mission_source(args, link)
            mission_client.upload(link, mission, args.timeout, args.retries)
        print(f"uploaded {len(mission.items)} items to system {link.target_system}")
        return EXIT_OK
    if args.action == "download":
        if not args.file:
            raise UsageError("mission download needs the FILE to write (.plan, .waypoints or .txt)")
        file_format(args.file)
        with _open_link(args) as link:
            mission = mission_client.download(link, args.timeout, args.retries)
        save_mission(mission, args.file)
        home = "" if mission.home is None else " (with the vehicle's home position)"
        print(f"downloaded {len(mission.items)} items to {args.file}{home}")
        return EXIT_OK
    if args.action == "clear":
        if args.file:
            raise UsageError("mission clear takes no FILE")
        with _open_link(args) as link:
            mission_client.clear(link, args.timeout, args.retries)
        print("mission cleared")
        return EXIT_OK
    raise UsageError(f"unknown mission action {args.action!r}")


# --- fly ----------------------------------------------------------------------------------------------------------

def cmd_fly(args) -> int:
    from gcs_tools.fly import fly, format_reached
    from gcs_tools.missions import waypoints_enu

    needs_home_from_link = (not args.file and (args.rectangle or args.helix) and args.frame == "global"
                            and args.home is None)
    mission = None if needs_home_from_link else _mission_source(args)
    with _open_link(args) as link:
        if mission is None:
            mission = _mission_source(args, link)
        home = None
        if any(it.frame not in (1, 4) for it in mission.items):
            home = _vehicle_home(link)
        points, radii = waypoints_enu(mission, home, args.radius)
        n = points.shape[0]
        print(f"flying {n} waypoints at {args.speed:g} m/s (switching radius {radii[0]:g} m)", flush=True)
        reached = fly(link, points, radii, speed=args.speed, min_leg_time=args.min_leg_time, timeout_s=args.timeout,
                      link_timeout_s=args.link_timeout, position_hz=args.position_rate,
                      report=lambda r, n: print(format_reached(r, n), flush=True),
                      notice=lambda text: print(f"warning: {text}", file=sys.stderr, flush=True))
    print(f"all {len(reached)} waypoints reached")
    return EXIT_OK


# --- log ------------------------------------------------------------------------------------------------------------

def cmd_log(args) -> int:
    from gcs_tools.logger import Recorder, export_csv, parse_fields, request_rates

    if args.csv and not args.fields:
        raise UsageError("--csv needs --fields MESSAGE.field,...")
    fields = [f for f in (args.fields or "").split(",") if f.strip()]
    if fields:
        parse_fields(fields)
    if args.duration is not None and not args.duration > 0:
        raise UsageError("--duration must be > 0")
    out = Path(args.output)
    if out.suffix != ".tlog":
        raise UsageError(f"-o {out}: the log must be a .tlog file")
    with _open_link(args) as link:
        request_rates(link, dict(args.rate or []), args.stream_rate)
        rec = Recorder(link, out, args.duration, args.link_timeout)

        def stop(signum, frame):
            rec.stop()

        signal.signal(signal.SIGINT, stop)
        signal.signal(signal.SIGTERM, stop)
        print(f"logging {args.connection} to {out}" + (f" for {args.duration:g} s" if args.duration else
                                                        " (Ctrl-C to stop)"), flush=True)
        count = rec.run()
    print(f"{count} messages written to {out}")
    if args.csv:
        rows = export_csv(out, args.csv, fields)
        print(f"{rows} rows written to {args.csv}")
    return EXIT_OK


def cmd_csv(args) -> int:
    from gcs_tools.logger import export_csv, parse_fields

    fields = [f for f in args.fields.split(",") if f.strip()]
    parse_fields(fields)
    rows = export_csv(args.tlog, args.csv, fields)
    print(f"{rows} rows written to {args.csv}")
    return EXIT_OK


# --- errors / plot -------------------------------------------------------------------------------------------------

def cmd_errors(args) -> int:
    from gcs_tools.tlog_errors import tlog_mean_errors
    from protocol.mean_error import format_table

    if args.t_from is not None and args.t_to is not None and args.t_to < args.t_from:
        raise UsageError(f"--to {args.t_to:g} is before --from {args.t_from:g}")
    res = tlog_mean_errors(args.tlog, args.t_from, args.t_to, args.sysid)
    if args.json:
        doc = dict(res)
        doc["mean_errors"] = {k: (v if math.isfinite(v) else None) for k, v in res["mean_errors"].items()}
        doc["tlog"] = str(args.tlog)
        print(json.dumps(doc, indent=2))
    else:
        print(f"mean errors (Eq. 45) of {args.tlog}, system {res['sysid']}"
              + ("" if args.t_from is None and args.t_to is None else
                 f", t in [{'start' if args.t_from is None else f'{args.t_from:g}'}, "
                 f"{'end' if args.t_to is None else f'{args.t_to:g}'}] s") + ":")
        print(format_table({args.label: res["mean_errors"]}))
        for col, why in res["missing"].items():
            print(f"{col}: not computed: missing {', '.join(why)}")
    return EXIT_OK


def cmd_plot(args) -> int:
    from gcs_tools.plots import plot_tlog
    from protocol.mission_files import load_mission

    mission = load_mission(args.mission) if args.mission else None
    written, skipped = plot_tlog(args.tlog, args.output, mission, args.title)
    for p in written:
        print(p)
    for name, why in skipped.items():
        print(f"{name}: skipped ({why})")
    if not written:
        raise OperationError(f"{args.tlog}: nothing to plot")
    return EXIT_OK


# --- stability --------------------------------------------------------------------------------------------------

def cmd_stability(args) -> int:
    from gcs_tools.stability.command import run

    return run(args)


# --- parser ---------------------------------------------------------------------------------------------------------

def _link_args(p) -> None:
    p.add_argument("connection", help="pymavlink connection string, e.g. tcp:127.0.0.1:5760 or udpin:0.0.0.0:14550")
    p.add_argument("--sysid", type=int, help="vehicle system id (default: the first vehicle heard)")
    p.add_argument("--heartbeat-timeout", type=_positive, default=10.0, help="seconds to wait for the vehicle: %(default)s")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0],
                                     epilog="exit codes: 0 ok, 1 operation failed, 2 bad usage or input")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("mission", help="upload, download or clear the vehicle's mission; make mission files",
                       description="Mission transfer (MAVLink mission protocol) and the paper's missions. FILE is a "
                                   "QGroundControl .plan or a QGC WPL 110 file (.waypoints/.txt); WPL line 0 is the "
                                   "home position, lines 1..N are items 0..N-1, every item is flown.")
    p.add_argument("action", choices=("upload", "download", "clear", "make"))
    p.add_argument("connection", nargs="?", help="pymavlink connection string (not for make)")
    p.add_argument("file", nargs="?", help="mission file (.plan, .waypoints, .txt)")
    p.add_argument("--sysid", type=int)
    p.add_argument("--heartbeat-timeout", type=_positive, default=10.0)
    p.add_argument("--timeout", type=_positive, default=1.5, help="mission protocol timeout per message (s): %(default)s")
    p.add_argument("--retries", type=int, default=5, help="mission protocol retries: %(default)s")
    _add_generator_args(p)
    p.set_defaults(func=cmd_mission)

    p = sub.add_parser("fly", help="fly waypoints from the ground with the 8 cm switching of Sec. 4-4",
                       description="Streams SET_POSITION_TARGET_LOCAL_NED along the virtual line of Sec. 4-4 and "
                                   "switches on LOCAL_POSITION_NED (protocol.waypoint_switching). Arms if needed. "
                                   "Exit 0 when every waypoint is reached, 1 on timeout or link loss.")
    _link_args(p)
    p.add_argument("file", nargs="?", help="mission file (.plan, .waypoints, .txt): every item is flown")
    p.add_argument("--speed", type=_positive, default=0.5, help="leg speed sizing each virtual line (m/s): %(default)s")
    p.add_argument("--min-leg-time", type=_positive, default=1.0, help="shortest leg duration (s): %(default)s")
    p.add_argument("--timeout", type=_positive, default=600.0, help="give up after this many seconds: %(default)s")
    p.add_argument("--link-timeout", type=_positive, default=5.0,
                   help="link lost after this many seconds without LOCAL_POSITION_NED: %(default)s")
    p.add_argument("--position-rate", type=_positive, default=20.0,
                   help="LOCAL_POSITION_NED rate to request (Hz of vehicle time): %(default)s")
    _add_generator_args(p)
    p.set_defaults(func=cmd_fly)

    p = sub.add_parser("log", help="record telemetry as a .tlog (optionally CSV of chosen fields)")
    _link_args(p)
    p.add_argument("-o", "--output", required=True, help="the .tlog to write")
    p.add_argument("--duration", type=float, help="stop after this many seconds (default: until Ctrl-C / SIGTERM)")
    p.add_argument("--csv", help="also export --fields to this CSV at the end")
    p.add_argument("--fields", help="comma-separated MESSAGE.field list, e.g. ATTITUDE.roll,LOCAL_POSITION_NED.x")
    p.add_argument("--rate", type=_rate, action="append", metavar="MESSAGE=HZ",
                   help="request a message rate with SET_MESSAGE_INTERVAL (repeatable)")
    p.add_argument("--stream-rate", type=float, metavar="HZ", help="request every stream at HZ (REQUEST_DATA_STREAM)")
    p.add_argument("--link-timeout", type=_positive, default=5.0, help="fail after this many silent seconds: %(default)s")
    p.set_defaults(func=cmd_log)

    p = sub.add_parser("csv", help="export chosen fields of a .tlog as CSV")
    p.add_argument("tlog")
    p.add_argument("--csv", required=True, help="CSV file to write")
    p.add_argument("--fields", required=True, help="comma-separated MESSAGE.field list")
    p.set_defaults(func=cmd_csv)

    p = sub.add_parser("errors", help="the mean errors of Eq. 45 (Table 6 layout) from a .tlog",
                       description="phi, theta, psi from ATTITUDE vs ATTITUDE_TARGET; X, Y, Z from "
                                   "LOCAL_POSITION_NED vs POSITION_TARGET_LOCAL_NED (latest target at or before each "
                                   "sample by time_boot_ms). Exit 1 when no column can be computed.")
    p.add_argument("tlog")
    p.add_argument("--from", dest="t_from", type=_number, metavar="S", help="window start (s of time_boot_ms)")
    p.add_argument("--to", dest="t_to", type=_number, metavar="S", help="window end (s of time_boot_ms)")
    p.add_argument("--sysid", type=int, help="vehicle system id (default: the first in the log)")
    p.add_argument("--label", default="run", help="row label in the table: %(default)s")
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.set_defaults(func=cmd_errors)

    p = sub.add_parser("plot", help="PNG plots of a .tlog",
                       description="Writes attitude.png (phi, theta, psi vs desired), position.png (X, Y, Z vs time), "
                                   "xy_path.png (with the waypoints' switching circles), path_3d.png (flown and "
                                   "desired path in 3D: the helix of Eq. 46), errors.png (attitude and position "
                                   "errors vs time, with each mean |e| of Eq. 45), thrusts.png and load_cells.png, "
                                   "as far as the log's messages allow. Titles name the run (scenario, strategy, "
                                   "airframe, seed) from the log of `rig-emulator simulate --out run.tlog`, else "
                                   "--title, else the file name.")
    p.add_argument("tlog")
    p.add_argument("-o", "--output", required=True, help="directory for the PNGs")
    p.add_argument("--mission", help="mission file for the XY plot's waypoints (default: the log's mission items)")
    p.add_argument("--title", help="what the titles name the run when the log does not say (e.g. 'helix, smc-flc, "
                                   "seed 1'; default: the file name)")
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser("stability", help="stability analysis of the FLC attitude gains (Eq. 16-32)",
                       description="Fits the planes of Eq. 16 to the FLC surfaces, solves the LMI of Eq. 32 (cvxpy, "
                                   "cross-checked with scipy) and computes R2 of Eq. 31. Exit 0 when the LMI derived "
                                   "from Eq. 19-25 is feasible, 1 when it is not (the reason is printed) or cvxpy is "
                                   "missing, 2 for bad parameters.")
    from gcs_tools.stability.command import add_arguments as _stability_arguments

    _stability_arguments(p)
    p.set_defaults(func=cmd_stability)

    from gcs_tools.param_cli import add_param_parser

    add_param_parser(sub)  # rig-gcs param list|get|set|save|load

    from gcs_tools.reproduce.cli import add_parser as add_reproduce_parser

    add_reproduce_parser(sub)  # rig-gcs reproduce -o DIR

    from gcs_tools.identify.cli import add_parser as add_identify_parser

    add_identify_parser(sub)  # rig-gcs identify
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # the command line, for files that say how they were made
    if args.command == "mission" and args.action != "make" and not args.connection:
        parser.error(f"mission {args.action} needs a CONNECTION")
    if args.command == "mission" and args.action == "make" and args.connection and not args.file:
        args.file, args.connection = args.connection, None  # `mission make FILE`
    try:
        return args.func(args)
    except GcsError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 1
    except BrokenPipeError:  # `rig-gcs param list ... | head`: the reader left; stop without a traceback
        from protocol.closed_pipe import quiet_exit_on_closed_pipe

        return quiet_exit_on_closed_pipe()
    except Exception as exc:
        files = sys.modules.get("protocol.mission_files")  # imported by the commands that read mission files
        if files is not None and isinstance(exc, files.MissionFileError):
            print(f"{PROG}: error: {exc}", file=sys.stderr)
            return EXIT_USAGE
        raise


if __name__ == "__main__":
    sys.exit(main())
