"""Command-line options of ``rig-emulator serve`` (kept light: no physics imports)."""

from __future__ import annotations

import argparse

from protocol.geodesy import Home
from rig_emulator.link.px4_simulator.serve_px4 import add_px4_args

DEFAULT_ENDPOINTS = ("udpout:127.0.0.1:14550", "tcpin:127.0.0.1:5760")
INSTANCE_PORT_STEP = 10  # ArduPilot SITL's -I N: every port + 10 N
MAX_INSTANCE = 99


def instance_endpoints(instance: int) -> list[str]:
    """The default endpoints of instance N: UDP 14550 + 10 N out, TCP 5760 + 10 N in (as ``-I N``)."""
    out = []
    for url in DEFAULT_ENDPOINTS:
        head, port = url.rsplit(":", 1)
        out.append(f"{head}:{int(port) + INSTANCE_PORT_STEP * instance}")
    return out


def instance_sysid(instance: int) -> int:
    """System id of instance N: N + 1 (sim_vehicle.py's --auto-sysid for ``-I N``)."""
    return instance + 1


def instance_state_dir(instance: int) -> str:
    """State directory of instance N: ``rig-state`` for 0, ``rig-state-N`` otherwise."""
    return "rig-state" if instance == 0 else f"rig-state-{instance}"
#: Reading: the rig's site, matching the earth field of imu_array.toml (Tehran-like, 35.7 N 51.4 E).
DEFAULT_HOME = "35.7,51.4,1200"


def parse_home(text: str) -> Home:
    try:
        lat, lon, alt = (float(v) for v in text.split(","))
        return Home(lat, lon, alt)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"--home {text!r}: expected LAT,LON,ALT in degrees and metres ({exc})")


def parse_speedup(text: str) -> float:
    if text.strip().lower() == "max":
        return 0.0
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not value >= 0.0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"--speedup {text!r}: expected a number >= 0 or 'max'")
    return value


def add_serve_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--mavlink", action="append", default=[], metavar="URL",
                   help="endpoint as a mavutil connection string (repeatable); default: " + " and ".join(DEFAULT_ENDPOINTS))
    p.add_argument("--scenario", help="scenario preset whose parameters the rig starts with")
    p.add_argument("--instance", "-I", type=int, default=0, metavar="N",
                   help="run instance N beside others, as ArduPilot SITL's -I N: system id N + 1, default endpoints "
                        "udpout 14550 + 10 N and tcpin 5760 + 10 N, state directory rig-state-N (N = 0: the plain "
                        "defaults); --sysid, --mavlink and --state-dir override (0..%d)" % MAX_INSTANCE)
    p.add_argument("--sysid", type=int, default=None, help="MAVLink system id (default 1, or N + 1 with --instance N)")
    p.add_argument("--quiet", action="store_true",
                   help="no event lines on stdout (arming, modes, mission items, failsafes, faults)")
    p.add_argument("--home", type=parse_home, default=parse_home(DEFAULT_HOME), metavar="LAT,LON,ALT",
                   help="geodetic position of the local origin (default %s)" % DEFAULT_HOME)
    p.add_argument("--speedup", type=parse_speedup, default=1.0, metavar="X",
                   help="simulated seconds per wall second; 0 or 'max' = as fast as possible (default 1)")
    p.add_argument("--duration", type=float, help="stop after this many simulated seconds (default: run until a signal)")
    p.add_argument("--chunk-ms", type=float, default=5.0, help="simulated time per physics chunk at real time; faster runs use up to 4x this (default %(default)s)")
    p.add_argument("--start-paused", action="store_true",
                   help="hold the simulated clock at its start until a mission is started (MAV_CMD_MISSION_START or "
                        "AUTO.MISSION); commands are served meanwhile, so a scripted run (upload, arm, start) gives "
                        "the same flight whenever its commands arrive")
    p.add_argument("--timing-log", metavar="FILE.npz",
                   help="record each physics chunk's wall-clock times and write them to FILE at exit (jitter benchmark)")
    g = p.add_argument_group("state kept across restarts (parameters set over MAVLink, the mission, the signing clock)")
    g.add_argument("--state-dir", metavar="DIR", help="where (default ./rig-state, created if needed; one rig per directory)")
    g.add_argument("--wipe", action="store_true", help="discard the stored state and start from the configuration")
    g.add_argument("--no-persist", action="store_true", help="keep nothing: read and write no state directory")
    g = p.add_argument_group("MAVLink 2 signing (off unless a key is given)")
    g.add_argument("--signing-key", metavar="KEY",
                   help="PASSPHRASE (key = its SHA-256, as MAVProxy's `signing setup PASSPHRASE` and QGroundControl "
                        "derive it) or hex:<64 hex digits>; then all the rig sends is signed and all it receives must "
                        "be signed with the key (RADIO_STATUS excepted), else it is dropped and counted. "
                        "Other users can see command lines: prefer --signing-key-file")
    g.add_argument("--signing-key-file", metavar="PATH", help="a file whose first line is the KEY of --signing-key")
    add_px4_args(p)  # a flight stack in the loop
