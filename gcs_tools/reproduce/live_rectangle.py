"""Fig. 19 flown the way a ground station would: a rig process, the MAVLink mission protocol.

:func:`fly_rectangle` starts ``rig-emulator serve`` (a subprocess, TCP endpoint on a free
port) with ``--start-paused --speedup max``, and as a ground station:

1. waits for the rig's HEARTBEAT, turns every stream off (REQUEST_DATA_STREAM) and asks
   for the few it needs at 25 Hz of simulated time (SET_MESSAGE_INTERVAL);
2. uploads the 5 m x 3 m rectangle as MISSION_ITEM_INT items (the mission protocol of
   :mod:`gcs_tools.mission_client`, 8 cm acceptance radius);
3. arms and sends MAV_CMD_MISSION_START;
4. records the telemetry stamped up to D simulated seconds, then stops the rig.

Why it is bit-identical run after run: ``--start-paused`` holds the rig's simulated clock
at 0 until the mission starts, so nothing the rig computes depends on when the upload, arm
and start commands arrived; after the start no command is sent; every figure is taken
from the rig's own telemetry, stamped in simulated time. TCP loses nothing; a gap in the
rig's MAVLink sequence numbers (the rig dropping messages for a slow reader) is an error,
not a silently different result.
"""

from __future__ import annotations

import subprocess
import time
from dataclasses import dataclass

import numpy as np

from gcs_tools import mission_client
from gcs_tools.errors import OperationError
from gcs_tools.link import Link
from gcs_tools.missions import mission_from_enu, rectangle_points
from gcs_tools.tlog_errors import attitude_series, position_series
from protocol.dialect import mavlink as M
from protocol.frames import mavlink_euler_to_paper

STREAM_HZ = 25.0  # one message of each stream per chunk
CHUNK_MS = 10.0  # --chunk-ms: 40 ms of simulation per chunk at --speedup max (each chunk costs the link a round)
ALTITUDE_M = 2.0  # the rectangle preset's altitude (rig_emulator/presets/scenarios/rectangle.toml)
WALL_TIMEOUT_S = 600.0
POLL_S = 0.02
RIG_EXIT_WAIT_S = 60.0  # wall seconds to wait for the rig's own exit at --duration before signalling it
SPARE_S = 5.0  # simulated seconds the rig runs past the recorded flight (the record ends at the first later message)
FIELDS = {
    "ATTITUDE": ("time_boot_ms", "roll", "pitch", "yaw"),
    "ATTITUDE_TARGET": ("time_boot_ms", "type_mask", "q"),
    "LOCAL_POSITION_NED": ("time_boot_ms", "x", "y", "z"),
    "POSITION_TARGET_LOCAL_NED": ("time_boot_ms", "type_mask", "x", "y", "z"),
    "SERVO_OUTPUT_RAW": ("time_usec", "servo1_raw", "servo2_raw", "servo3_raw", "servo4_raw"),
}


@dataclass
class LiveRun:
    """What the ground station recorded (SI, the paper's frames, simulated time)."""

    waypoints: np.ndarray  # (N, 3) world ENU
    radius_m: float
    duration_s: float
    t_pos: np.ndarray
    pos: np.ndarray  # (n, 3) the rig's own virtual position (LOCAL_POSITION_NED), ENU
    pos_target: np.ndarray  # (n, 3) POSITION_TARGET_LOCAL_NED paired to each sample, ENU
    t_att: np.ndarray
    euler: np.ndarray  # (n, 3) paper phi, theta, psi (rad)
    euler_target: np.ndarray
    reached: list  # [(seq, t_s)]: MISSION_ITEM_REACHED and the stamp of the chunk it came in
    stream_hz: float  # rate of each telemetry stream (simulated time)
    messages: int  # telemetry messages recorded (the streams above, stamped in simulated time)
    rig_exit_code: int


def _arrays(messages: dict) -> dict:
    out = {}
    for name, fields in FIELDS.items():
        rows = messages.get(name, [])
        cols = {}
        for f in fields:
            if f == "q":
                for i in range(4):
                    cols[f"q[{i}]"] = np.array([m.q[i] for m in rows], dtype=float)
            else:
                cols[f] = np.array([getattr(m, f) for m in rows], dtype=float)
        out[name] = cols
    return out


def _configure_streams(link: Link) -> None:
    link.request_data_streams(0)  # every stream off (no ACK in that protocol; the next commands queue behind it)
    for name in FIELDS:
        link.set_message_rate(getattr(M, f"MAVLINK_MSG_ID_{name}"), STREAM_HZ)


def _toml_value(value) -> str:
    """A parameter value as the TOML text ``--set`` parses (numbers, strings, booleans, lists)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + "}"
    return repr(value)


def fly_rectangle(seed: int, duration_s: float, strategy: str = "smc-flc", width: float = 5.0, height: float = 3.0,
                  radius: float = 0.08, airframe: str = "hilms", overrides: dict | None = None) -> LiveRun:
    """Fly the Fig. 19 rectangle on a rig process over MAVLink (see the module docstring), on the
    plant ``airframe`` with parameter ``overrides`` (dotted key -> TOML-expressible value)."""
    from rig_emulator.testing.rig import RigProcess, client_url

    points = rectangle_points(width, height, ALTITUDE_M)
    mission = mission_from_enu(points, radius, "local")
    # --duration: the rig stops by itself a little after the flight is recorded, even if this process dies
    args = ["--start-paused", "--no-persist", "--chunk-ms", repr(CHUNK_MS), "--duration", repr(duration_s + SPARE_S),
            "--scenario", "rectangle", "--airframe", airframe,
            "--set", f"sim.seed={int(seed)}", "--set", f"control.strategy={strategy}"]
    for key, value in (overrides or {}).items():
        args += ["--set", f"{key}={_toml_value(value)}"]
    try:
        rig = RigProcess(speedup="max", args=args)
    except RuntimeError as exc:
        raise OperationError(f"rectangle: the rig process did not start: {exc}") from None
    try:
        link = Link(client_url(rig.tcp_url))
        try:
            link.wait_vehicle(30.0)
            _configure_streams(link)
            mission_client.upload(link, mission)
            link.arm()
            link.command_ok(M.MAV_CMD_MISSION_START, 0.0, 0.0, what="MISSION_START")
            messages, reached, count = _record(link, duration_s, lambda: rig.proc.poll() is None)
            lost = link.conn.mav_loss
        finally:
            link.close()
    finally:
        # The rig ends itself at --duration (moments after the flight at --speedup max); a
        # SIGTERM sent while it is already shutting down would kill it with -15 after its
        # handlers are restored, so wait for its own exit first and signal only if it hangs.
        try:
            rig.proc.wait(RIG_EXIT_WAIT_S)
        except subprocess.TimeoutExpired:
            pass
        code = rig.stop()
    if lost:
        raise OperationError(f"rectangle: {lost} telemetry messages were lost (MAVLink sequence gaps); the figures "
                             "would not be the rig's whole flight")
    if code != 0:
        raise OperationError(f"rectangle: the rig exited with {code}: {' / '.join(rig.output[-3:])}")
    arrays = _arrays(messages)
    pos = position_series(arrays)
    att = attitude_series(arrays)
    euler = np.column_stack(mavlink_euler_to_paper(att["actual"][:, 0], att["actual"][:, 1], att["actual"][:, 2]))
    target = np.column_stack(mavlink_euler_to_paper(att["target"][:, 0], att["target"][:, 1], att["target"][:, 2]))
    return LiveRun(waypoints=points, radius_m=radius, duration_s=float(duration_s), t_pos=pos["t"],
                   pos=pos["actual"], pos_target=pos["target"], t_att=att["t"], euler=euler, euler_target=target,
                   reached=reached, stream_hz=STREAM_HZ, messages=count, rig_exit_code=code)


def _stamp(msg) -> float:
    return msg.time_usec * 1e-6 if msg.get_type() == "SERVO_OUTPUT_RAW" else msg.time_boot_ms * 1e-3


def _record(link: Link, duration_s: float, alive=lambda: True):
    """Messages by type stamped up to ``duration_s``: read until the first one stamped after it.

    The rig sends each chunk's messages after the chunk, in simulated-time order over one TCP
    stream, so everything stamped up to ``duration_s`` has arrived by then.
    """
    messages = {name: [] for name in FIELDS}
    reached, pending = [], []
    count = 0
    last_stamp = 0.0
    deadline = time.monotonic() + WALL_TIMEOUT_S
    while True:
        if time.monotonic() > deadline:
            raise OperationError(f"rectangle: the rig did not fly {duration_s:g} simulated seconds in "
                                 f"{WALL_TIMEOUT_S:g} s")
        link.heartbeat_if_due()
        msg = link.conn.recv_match(blocking=False)
        if msg is None:
            if not alive():
                raise OperationError(f"rectangle: the rig process ended before {duration_s:g} simulated seconds")
            # read in batches rather than being woken for every chunk the rig sends (a few kB per poll)
            time.sleep(POLL_S)
            continue
        if msg.get_srcSystem() != link.target_system:
            continue
        kind = msg.get_type()
        if kind == "MISSION_ITEM_REACHED":
            pending.append(msg.seq)
            continue
        if kind not in messages:
            continue
        stamp = _stamp(msg)
        if stamp > duration_s + 1e-9:
            break
        messages[kind].append(msg)
        count += 1
        if pending and stamp > last_stamp:
            reached.extend((seq, stamp) for seq in pending)  # the end of the chunk it was reached in
            pending = []
        last_stamp = max(last_stamp, stamp)
    reached.extend((seq, stamp) for seq in pending)
    return messages, reached, count
