"""The ``--px4-simulator`` options of ``rig-emulator serve`` and the serve path they select."""

from __future__ import annotations

import argparse
import os

from rig_emulator.config.loader import ConfigError
from rig_emulator.link.px4_simulator.transport import DEFAULT_HOST, DEFAULT_PORT, TransportError, open_transport, parse_spec

DEFAULT_RATE_HZ = 250.0
#: PX4 SITL's airframe for the rig (geometry and tuning, ``param set-default`` lines): copied into
#: PX4's ``build/px4_sitl_default/etc/init.d-posix/airframes/``, PX4 starts it as ``PX4_SIM_MODEL=none_hilms``
AIRFRAME_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "10090_none_hilms")


def add_px4_args(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("a flight stack in the loop (PX4's Simulator MAVLink API, in lockstep; docs/how-to/flight-stacks.md)")
    g.add_argument("--px4-simulator", nargs="?", const=f"{DEFAULT_HOST}:{DEFAULT_PORT}", metavar="[HOST:]PORT",
                   help=f"be the simulator of a flight stack: listen for its TCP connection (default "
                        f"{DEFAULT_HOST}:{DEFAULT_PORT}, where PX4 SITL connects) or use serial:DEVICE[:BAUD] for a "
                        "flight controller board in HIL; HIL_SENSOR/HIL_GPS/HIL_STATE_QUATERNION out, "
                        "HIL_ACTUATOR_CONTROLS in, one plant step per actuator message. The rig's own controllers "
                        "are off; --mavlink endpoints keep serving the rig's telemetry. PX4 SITL needs the rig's geometry "
                        "and tuning: the airframe installed with the rig as "
                        "rig_emulator/link/px4_simulator/10090_none_hilms (the rig prints its path at start-up)")
    g.add_argument("--px4-rate", type=float, default=DEFAULT_RATE_HZ, metavar="HZ",
                   help="the flight stack's step rate, a divisor of the physics rate (default %(default)g, PX4's)")
    g.add_argument("--px4-all-fields", action="store_true",
                   help="flag every HIL_SENSOR field as updated (0x1FFF) at every step, as jMAVSim does, instead of "
                        "only the sensors that sampled during the step")


def check_px4_args(args) -> None:
    """Options that do not go with ``--px4-simulator`` (or need it), refused before the rig is built."""
    if not getattr(args, "px4_simulator", None):
        return
    for flag, value in (("--start-paused", args.start_paused), ("--timing-log", args.timing_log)):
        if value:
            raise ConfigError(f"{flag} does not apply with --px4-simulator: the flight stack steps the plant")
    if not (args.px4_rate > 0.0 and args.px4_rate < 1e6):
        raise ConfigError(f"--px4-rate {args.px4_rate:g}: must be > 0")
    try:
        parse_spec(args.px4_simulator)
    except TransportError as exc:
        raise ConfigError(str(exc)) from exc


def serve_px4(args, ground, rig, log):
    """The rig as the flight stack's simulator (:class:`Px4SimulatorServer`; the ground link
    ``ground`` is up already); the caller runs and closes it."""
    from rig_emulator.link.px4_simulator.server import Px4SimulatorServer
    from rig_emulator.simulation.lockstep import LockstepPlant

    try:
        transport = open_transport(args.px4_simulator)
    except TransportError as exc:
        raise ConfigError(str(exc)) from exc
    try:
        plant = LockstepPlant(rig, args.px4_rate, args.home.alt_m)
        px4 = Px4SimulatorServer(ground, transport, plant, args.home, speedup=args.speedup,
                                 all_fields=args.px4_all_fields, log=log)
    except Exception:
        transport.close()
        raise
    return px4
