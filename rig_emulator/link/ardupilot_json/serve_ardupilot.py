"""The ``--ardupilot-json`` options of ``rig-emulator serve`` and the serve path they select."""

from __future__ import annotations

import argparse
import os

from rig_emulator.config.loader import ConfigError

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 9002  # ArduPilot SIM_JSON's control port; + 10 N for SITL's -I N
INSTANCE_PORT_STEP = 10
#: the rig's ground link with --ardupilot-json and no --mavlink (+ 10 N with --instance N): ArduPilot SITL
#: listens on TCP 5760 (+ 10 N) itself, and sends its own telemetry to ground stations on UDP 14550
GROUND_TCP_PORT = 5790
#: ArduCopter's parameters for the rig (frame, motor routing, thrust curve): ``--defaults``
PARAM_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "hilms.parm")


def add_ardupilot_args(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("ArduPilot in the loop (ArduPilot SITL's JSON simulator interface, in lockstep; "
                             "docs/how-to/flight-stacks.md)")
    g.add_argument("--ardupilot-json", nargs="?", const="", metavar="[HOST:]PORT",
                   help=f"be the physics of ArduPilot SITL started with --model JSON:HOST: answer its servo "
                        f"packets on UDP (default {DEFAULT_HOST}:{DEFAULT_PORT}, + 10 N with --instance N, as "
                        f"SITL's -I N) with the rig's state as JSON, one plant step per new frame. The rig's own "
                        f"controllers are off; --mavlink endpoints keep serving the rig's telemetry (default "
                        f"tcpin:127.0.0.1:{GROUND_TCP_PORT} + 10 N: SITL itself listens on 5760 + 10 N). ArduCopter "
                        "needs the rig's frame and motor routing: --defaults ...,PATH/hilms.parm (the file installed "
                        "with the rig as rig_emulator/link/ardupilot_json/hilms.parm; the rig prints its path at start-up)")
    g.add_argument("--ardupilot-rate", type=float, default=None, metavar="HZ",
                   help="the plant's step per ArduPilot frame, a divisor of the physics rate (default: the physics "
                        "rate, 1000 Hz: one physics step per frame)")


def ground_endpoints(instance: int = 0) -> list[str]:
    """The rig's ground link beside ArduPilot SITL ``-I instance`` when ``--mavlink`` is not given."""
    return [f"tcpin:127.0.0.1:{GROUND_TCP_PORT + INSTANCE_PORT_STEP * instance}"]


def parse_spec(text: str, instance: int = 0) -> tuple[str, int]:
    """(host, port) of an ``--ardupilot-json`` value ('' = the default for the instance)."""
    text = text.strip()
    default_port = DEFAULT_PORT + INSTANCE_PORT_STEP * instance
    if not text:
        return DEFAULT_HOST, default_port
    host, sep, port = text.rpartition(":")
    if not sep:
        host = DEFAULT_HOST
    if not port.isdigit() or not 0 <= int(port) <= 65535 or (sep and not host):
        raise ConfigError(f"--ardupilot-json {text!r}: expected [HOST:]PORT (e.g. 9002 or 0.0.0.0:9002)")
    return host, int(port)


def check_ardupilot_args(args) -> None:
    """Options that do not go with ``--ardupilot-json``, refused before the rig is built."""
    if getattr(args, "ardupilot_json", None) is None:
        if getattr(args, "ardupilot_rate", None) is not None:
            raise ConfigError("--ardupilot-rate needs --ardupilot-json")
        return
    if getattr(args, "px4_simulator", None):
        raise ConfigError("--ardupilot-json and --px4-simulator: one flight stack at a time")
    for flag, value in (("--start-paused", args.start_paused), ("--timing-log", args.timing_log)):
        if value:
            raise ConfigError(f"{flag} does not apply with --ardupilot-json: ArduPilot steps the plant")
    rate = args.ardupilot_rate
    if rate is not None and not (rate > 0.0 and rate < 1e6):
        raise ConfigError(f"--ardupilot-rate {rate:g}: must be > 0")
    parse_spec(args.ardupilot_json, args.instance)


def serve_ardupilot(args, ground, rig, log):
    """The rig as ArduPilot's physics (:class:`JsonPhysicsServer`; the ground link ``ground`` is
    up already); the caller runs and closes it."""
    from rig_emulator.link.ardupilot_json.server import JsonPhysicsServer
    from rig_emulator.simulation.lockstep import LockstepPlant

    host, port = parse_spec(args.ardupilot_json, args.instance)
    rate = args.ardupilot_rate or float(rig.cfg["sim.physics_rate_hz"])
    plant = LockstepPlant(rig, rate, args.home.alt_m, rate_option="--ardupilot-rate")
    try:
        return JsonPhysicsServer(ground, host, port, plant, log=log)
    except OSError as exc:
        raise ConfigError(f"--ardupilot-json {host}:{port}: {exc.strerror or exc}") from exc
