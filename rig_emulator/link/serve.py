"""``rig-emulator serve`` (also plain ``rig-emulator``): the rig on MAVLink.

Defaults follow SITL conventions: ``udpout:127.0.0.1:14550`` (QGroundControl picks the rig
up with no configuration) and ``tcpin:127.0.0.1:5760`` (scripts, MAVProxy). Repeat
``--mavlink`` to choose the endpoints instead. ``--speedup 1`` is real time, larger is
faster, ``0`` or ``max`` runs as fast as possible. SIGINT/SIGTERM stop the rig cleanly
(exit 0). On start one line per endpoint is printed, ``rig-emulator: serving URL`` with
the bound port, so scripts can bind port 0 and read the port back.

Parameters set over MAVLink and the mission are kept in ``./rig-state`` (``--state-dir``,
``--wipe``, ``--no-persist``; :mod:`rig_emulator.link.state.directory`); ``--signing-key`` turns
MAVLink 2 signing on (:mod:`rig_emulator.link.signing.policy`).

``--instance N`` (``-I N``) runs a rig beside others as ArduPilot SITL's ``-I N`` does:
system id N + 1, default endpoints ``udpout:127.0.0.1:14550+10N`` and
``tcpin:127.0.0.1:5760+10N``, state directory ``rig-state-N`` (``--sysid``, ``--mavlink``
and ``--state-dir`` still override). Events (arming, mode changes, mission items, faults,
failsafes, landings) are printed one per line, ``rig-emulator: [  t_sim] text``
(:mod:`rig_emulator.link.commands.console`; ``--quiet`` turns them off).

``--start-paused`` holds the simulated clock at 0 until a mission is started (MISSION_START
or AUTO.MISSION): a script uploads, arms and starts at its own pace and the flight, stamped
in simulated time from the start, is the same run after run (``rig-gcs reproduce`` flies
the Fig. 19 rectangle this way).

Start-up: the endpoints open first and the ``rig-emulator: serving URL`` lines are
printed at once; until the rig is built and its step loop compiled (minutes with a cold numba
cache, about a second with a warm one) a :class:`~rig_emulator.link.boot.BootLink` speaks for
it: HEARTBEAT with MAV_STATE_BOOT within the first seconds, STATUSTEXT "starting: compiling
the step loop", commands TEMPORARILY_REJECTED (AUTOPILOT_VERSION answered). Then the rig takes
the same sockets and peers over, prints ``rig-emulator: ready ...`` and its HEARTBEAT says
MAV_STATE_STANDBY. Test seam: the environment variable ``HILMS_SERVE_BOOT_DELAY_S`` (seconds)
delays building the rig by that much, standing in for a slow cold compile with a warm cache.
"""

from __future__ import annotations

import math
import os
import signal
import time
from typing import TYPE_CHECKING

from rig_emulator.config.loader import ConfigError, load_config
from rig_emulator.link.boot import BootLink
from rig_emulator.link.endpoints.sockets import EndpointError, open_endpoint
from rig_emulator.link.ardupilot_json.serve_ardupilot import check_ardupilot_args
from rig_emulator.link.px4_simulator.serve_px4 import check_px4_args
from rig_emulator.link.serve_args import DEFAULT_ENDPOINTS
from rig_emulator.link.serve_args import MAX_INSTANCE, instance_endpoints, instance_sysid, instance_state_dir
from rig_emulator.link.serve_setup import make_signing, open_state, signing_key_from_args

if TYPE_CHECKING:
    from rig_emulator.simulation.live import LiveRig

BOOT_DELAY_ENV = "HILMS_SERVE_BOOT_DELAY_S"  # test seam: see the module docstring


def prepare_rig(cfg, controller=None) -> LiveRig:
    """A disarmed rig, compiled, holding its initial position (arming makes it hover there);
    ``controller``: a controller plug-in object flying it instead of the config's ``controller.plugin``."""
    from rig_emulator.simulation.live import LiveRig  # noqa: F811 (imported here: after the boot link speaks)

    rig = LiveRig(cfg, controller=controller)
    rig.warm_up()
    rig.set_position_target(list(cfg["initial.position"]))
    return rig


def chunk_seconds(chunk_ms: float, speedup: float) -> float:
    """Simulated time per physics chunk.

    Each chunk costs a fixed Python overhead (the compiled call, one snapshot, the link), so
    faster-than-real-time runs step in longer chunks: the chunk grows with the speed-up up to
    4x (``speedup`` 0 means as fast as possible). Stream rates stay capped at one message per
    chunk (50 Hz with the default 5 ms x 4).
    """
    factor = 4.0 if speedup <= 0.0 else min(max(speedup, 1.0), 4.0)
    return chunk_ms / 1000.0 * factor


def cmd_serve(args, overrides: dict) -> int:
    if not 0 <= args.instance <= MAX_INSTANCE:
        raise ConfigError(f"--instance {args.instance}: must be 0..{MAX_INSTANCE}")
    if args.sysid is None:
        args.sysid = instance_sysid(args.instance)
    if args.state_dir is None and args.instance and not args.no_persist:
        args.state_dir = instance_state_dir(args.instance)
    if not 1 <= args.sysid <= 255:
        raise ConfigError(f"--sysid {args.sysid}: must be 1..255")
    if args.duration is not None and not args.duration > 0:
        raise ConfigError(f"--duration {args.duration}: must be > 0")
    if not 0.1 <= args.chunk_ms <= 100.0:
        raise ConfigError(f"--chunk-ms {args.chunk_ms}: must be in [0.1, 100]")
    if args.timing_log and not os.path.isdir(os.path.dirname(os.path.abspath(args.timing_log))):
        raise ConfigError(f"--timing-log {args.timing_log}: its directory does not exist")
    check_px4_args(args)
    check_ardupilot_args(args)
    key, key_source = signing_key_from_args(args, _log)
    state = open_state(args, args.home)
    try:
        return _serve(args, overrides, state, make_signing(key, key_source, state, _log))
    finally:
        if state is not None:
            state.close()


def default_endpoints(args) -> list[str]:
    """The ground link's endpoints when ``--mavlink`` is not given: the instance's, or with
    ``--ardupilot-json`` one TCP port beside ArduPilot SITL's (which listens on 5760 + 10 N itself)."""
    if getattr(args, "ardupilot_json", None) is not None:
        from rig_emulator.link.ardupilot_json.serve_ardupilot import ground_endpoints

        return ground_endpoints(args.instance)
    return instance_endpoints(args.instance)


def _log(text: str) -> None:
    print(f"rig-emulator: {text}", flush=True)


def _open_endpoints(specs: list[str]) -> list:
    endpoints = []
    try:
        for spec in specs:
            endpoints.append(open_endpoint(spec))
    except EndpointError as exc:
        for ep in endpoints:
            ep.close()
        raise ConfigError(str(exc)) from exc
    return endpoints


def _build_server(args, overrides: dict, state, signing, endpoints):
    """The rig, compiled, and its server on ``endpoints`` (the boot link speaks meanwhile)."""
    from rig_emulator.compile_notice import compile_notice
    from rig_emulator.link.server import RigServer
    from rig_emulator.physics.hardware import rest_attitude

    delay = float(os.environ.get(BOOT_DELAY_ENV, "0") or 0.0)
    if delay > 0.0:
        time.sleep(delay)
    cfg = load_config(airframe=args.airframe, scenario=args.scenario, files=args.config, overrides=overrides)
    with compile_notice(cfg=cfg):
        rig = prepare_rig(cfg)
    rest = rest_attitude(rig.sim.pp.hw, rig.sim.pp.g, math.radians(cfg["initial.euler_deg"][2]))
    if rest is not None:
        _log(f"disarmed, the rig hangs at roll {math.degrees(rest[0]):.1f} deg, pitch {math.degrees(rest[1]):.1f} deg "
             f"on its joint (its centre of gravity is off the joint; arming levels it)")
    server = RigServer(rig, endpoints, sysid=args.sysid, home=args.home, speedup=args.speedup,
                       chunk_s=chunk_seconds(args.chunk_ms, args.speedup), signing=signing, state=state,
                       console=not getattr(args, "quiet", False))
    if state is not None:
        _log(state.restore(server))
    return rig, server


def _serve(args, overrides: dict, state, signing) -> int:
    t_start = time.monotonic()
    endpoints = _open_endpoints(args.mavlink or default_endpoints(args))
    boot = BootLink(endpoints, sysid=args.sysid).start()
    for ep in endpoints:
        print(f"rig-emulator: serving {ep.url}", flush=True)
    try:
        rig, server = _build_server(args, overrides, state, signing, endpoints)
    except BaseException:
        boot.hand_over()
        for ep in endpoints:
            ep.close()
        raise
    server.adopt_peers(boot.hand_over())
    _log(f"ready: the rig runs ({time.monotonic() - t_start:.1f} s after start; "
         f"{boot.rejected} commands were refused while it started)")
    server.hold_clock = bool(getattr(args, "start_paused", False))
    if args.timing_log:
        from rig_emulator.link.loop_timing import LoopTiming

        server.timing = LoopTiming(server.chunk_s, args.speedup)
    runner = server
    try:  # a flight stack steps the plant (px4_simulator/, ardupilot_json/)
        if getattr(args, "px4_simulator", None):
            from rig_emulator.link.px4_simulator.serve_px4 import AIRFRAME_FILE, serve_px4

            runner = serve_px4(args, server, rig, _log)
            print(f"rig-emulator: px4 simulator on {runner.transport.url}", flush=True)
            print(f"rig-emulator: PX4 SITL airframe for the rig: {AIRFRAME_FILE} (copy it into PX4's "
                  "build/px4_sitl_default/etc/init.d-posix/airframes/, start PX4 with PX4_SIM_MODEL=none_hilms)",
                  flush=True)
        elif getattr(args, "ardupilot_json", None) is not None:
            from rig_emulator.link.ardupilot_json.serve_ardupilot import PARAM_FILE, serve_ardupilot

            runner = serve_ardupilot(args, server, rig, _log)
            print(f"rig-emulator: ardupilot json physics on {runner.url} (ArduCopter: --model JSON:HOST "
                  f"--defaults ...,{PARAM_FILE})", flush=True)
    except ConfigError:
        server.close()
        raise
    previous = {s: signal.signal(s, lambda *_: runner.stop()) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        runner.run(args.duration)
    finally:
        if runner is not server:
            runner.close()
        server.close()
        if signing is not None:
            signing.close()
        for s, handler in previous.items():
            signal.signal(s, handler)
        if server.timing is not None:
            server.timing.reanchors = server.overruns
            server.timing.write(args.timing_log)
    c = server.counters
    print(f"rig-emulator: stopped at t = {rig.time_s:.3f} s; received {c.received}, sent {c.sent}, "
          f"dropped {dict(c.dropped)}", flush=True)
    return 0
