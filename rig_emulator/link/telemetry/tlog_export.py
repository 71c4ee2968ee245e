"""Telemetry logs (.tlog): the record writer, and a headless run written as the live rig streams it.

**Format.** A .tlog is what pymavlink's ``mavutil`` writes (``mavfile.recv_msg`` with a
``logfile``): for each message an 8-byte big-endian timestamp in microseconds since the
Unix epoch, its two low bits cleared (mavutil keeps them for the link number), followed
by the raw MAVLink frame exactly as pymavlink's generated dialect packs it. pymavlink's
``mavlogdump.py``, MAVExplorer and QGroundControl read it.

:class:`TlogWriter` writes each record with a single ``write`` system call on an
unbuffered file, so a logger killed at any moment (SIGKILL included) leaves a file that
ends after its last complete record.

**Headless runs.** :func:`export_tlog` turns a :class:`~rig_emulator.simulation.run.SimResult`
into the messages the live rig streams, built by the link's own message builders
(``telemetry_*.py``) from a :class:`~rig_emulator.simulation.live.RigSnapshot` per log row,
stamped with the simulated time (``time_boot_ms`` / ``time_usec`` and the record
timestamp = ``epoch_s`` + simulated time; SERVO_OUTPUT_RAW and the load cells' messages with the control
update and the load-cell sample their values come from, as the live rig stamps them), every message at the log rate
(``sim.log_rate_hz``; above 100 Hz only ATTITUDE, SERVO_OUTPUT_RAW and HILMS_LOAD_CELLS, the others at
100 Hz) and HEARTBEAT / HOME_POSITION once per simulated second.

Reading: the rig's own figures (:meth:`SimResult.mean_errors`) are computed from what the
controllers were fed (series ``pos``, ``euler``: the rig's estimates, or the truth with
``sensors.feedback = "ideal"``); a vehicle reports its estimates in ATTITUDE and
LOCAL_POSITION_NED, so the export puts ``pos``/``euler`` there and the true state
(``pos_true``/``euler_true``; the log has no true velocity and body rates, SIM_STATE
carries the recorded ``vel``/``omega`` there) in SIM_STATE. The live rig does the same
(its snapshot's ``true_*`` fields). HILMS_LOAD_CELLS and its NAMED_VALUE_FLOAT
mirror carry the filtered load-cell thrusts (``thrust_meas``). A waypoint scenario's
mission is written first as MISSION_COUNT + MISSION_ITEM_INT (MAV_FRAME_LOCAL_NED, the
switching radius in param2), as a ground station's log of a mission download holds it.
"""

from __future__ import annotations

import math
import os
import struct
from types import SimpleNamespace

import numpy as np

from protocol.atomic_file import atomic_path
from protocol.dialect import mavlink as M
from protocol.frames import enu_to_ned
from protocol.geodesy import Home
from protocol.run_label import label_chunks
from rig_emulator.link.telemetry import attitude as A
from rig_emulator.link.telemetry import position as P
from rig_emulator.link.telemetry import sensors as S
from rig_emulator.link.telemetry import status as T
from rig_emulator.link.endpoints.counters import LinkCounters
from rig_emulator.link.telemetry.ideal_sensors import load_sensor_model
from rig_emulator.link.commands.modes import OFFBOARD, FlightModes
from rig_emulator.link.telemetry.context import TelemetryContext
from rig_emulator.physics.rotation import quat_from_euler
from rig_emulator.simulation.live import RigSnapshot
from rig_emulator.simulation.run import last_update_us, step_time_us

DEFAULT_HOME = Home(35.7, 51.4, 1200.0)  # the live rig's default (rig_emulator/link/server.py)
COMPID = M.MAV_COMP_ID_AUTOPILOT1
MISSION_ITEM_LOCAL_SCALE = 1e4  # MISSION_ITEM_INT x/y in local frames: metres * 1e4

#: Streams written at every log row, in this order (builders of the live link); those not in
#: :data:`FULL_RATE_STREAMS` at most at :data:`OTHER_STREAMS_MAX_HZ`.
ROW_STREAMS = (
    ("attitude", A.attitude),
    ("attitude_target", A.attitude_target),
    ("local_position_ned", P.local_position_ned),
    ("position_target_local_ned", P.position_target_local_ned),
    ("hilms_controller_state", A.hilms_controller_state),
    ("servo_output_raw", T.servo_output_raw),
    ("hilms_load_cells", S.hilms_load_cells),
    ("named_value_float", S.named_value_float),
    ("global_position_int", P.global_position_int),
)


#: What the identification needs at the controller's rate (gcs_tools/identify/sysid_log.py): a log rate above
#: 100 Hz (the identification flight logs at 500 Hz) is for them; the other streams stay at a ground
#: station's usual rates, which keeps such a log a quarter of the size and its export as much faster.
FULL_RATE_STREAMS = ("attitude", "servo_output_raw", "hilms_load_cells")
OTHER_STREAMS_MAX_HZ = 100.0


def tlog_usec(t_unix_s: float) -> int:
    """The record timestamp mavutil writes: microseconds, the two low bits cleared."""
    return int(round(t_unix_s * 1e6)) & ~3


class TlogWriter:
    """Append MAVLink messages to a .tlog, one ``write`` per record (see the module doc).

    ``write(msg, t_unix_s)`` packs ``msg`` with this writer's own sequence numbers and source
    ids; ``write_raw(frame, t_unix_s)`` stores a frame received from a link unchanged.
    """

    def __init__(self, path, srcSystem: int = 1, srcComponent: int = COMPID, append: bool = False):
        flags = os.O_WRONLY | os.O_CREAT | (os.O_APPEND if append else os.O_TRUNC)
        self.fd = os.open(path, flags, 0o644)
        self.mav = M.MAVLink(None, srcSystem=srcSystem, srcComponent=srcComponent)
        self.count = 0
        self.bytes = 0

    def write_raw(self, frame: bytes, t_unix_s: float) -> None:
        record = struct.pack(">Q", tlog_usec(t_unix_s)) + bytes(frame)
        view = memoryview(record)
        while view:  # a regular file takes it in one call; loop only if the OS says otherwise
            n = os.write(self.fd, view)
            view = view[n:]
        self.count += 1
        self.bytes += len(record)

    def write(self, msg, t_unix_s: float) -> None:
        frame = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        self.write_raw(frame, t_unix_s)

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# --- headless run -> messages ---------------------------------------------------------------------------------

def _quat_of(euler) -> tuple:
    q = np.zeros(4)
    quat_from_euler(float(euler[0]), float(euler[1]), float(euler[2]), q)
    return tuple(float(v) for v in q)


def _t(v) -> tuple:
    if type(v) is list:  # a row of _row_lists: Python floats already
        return tuple(v)
    return tuple(float(a) for a in np.atleast_1d(v))


def _row_lists(series: dict) -> dict:
    """``series`` with every array as nested Python lists: :func:`row_snapshot` then reads a row's numbers
    as floats without making a numpy scalar of each (the same values, bit for bit)."""
    return {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in series.items()}


def row_snapshot(series: dict, i: int, guidance: str, physics_rate_hz: float | None = None,
                 ctrl_div: int = 1, cells_div: int = 1) -> RigSnapshot:
    """The snapshot of log row ``i``: the rig's estimates as it reports them, the truth in ``true_*``.

    With ``physics_rate_hz`` its stamp (``time_us``) comes from the step counter of the row
    (``t`` is k dt: k = round(t x rate)), as the live rig's does, and so do the stamps of the motor
    commands and the load-cell readings the row carries: the row is written after step k's sensing
    and control, so they are the last control update (every ``ctrl_div`` steps) and the last load-cell
    sample (every ``cells_div`` steps) at or before k."""
    s = series
    t = float(s["t"][i])
    time_us = commands_us = cells_us = None
    if physics_rate_hz is not None:
        k = round(t * physics_rate_hz)
        time_us = step_time_us(k, physics_rate_hz)
        commands_us = last_update_us(k, ctrl_div, physics_rate_hz)
        cells_us = last_update_us(k, cells_div, physics_rate_hz)
    euler = s["euler"][i]
    nan3 = (math.nan,) * 3
    pos_des = s["pos_des"][i]
    attitude_mode = s["mode"][i] == 1.0 or not all(math.isfinite(float(v)) for v in pos_des)
    return RigSnapshot(
        time_s=t, time_us=time_us, commands_time_us=commands_us, cells_time_us=cells_us, armed=True, position=_t(s["pos"][i]), velocity=_t(s["vel"][i]),
        quaternion=_quat_of(euler), euler=_t(euler), euler_rates=_t(s["euler_rate"][i]), body_rates=_t(s["omega"][i]),
        position_target=nan3 if attitude_mode else _t(pos_des),
        velocity_target=nan3 if attitude_mode else _t(s["vel_des"][i]),
        euler_target=_t(s["euler_des"][i]), euler_rate_target=_t(s["euler_rate_des"][i]),
        thrusts=_t(s["thrust_meas"][i]), thrust_commands=(math.nan,) * 4, voltage_commands=_t(s["v_cmd"][i]),
        rotor_speeds=(math.nan,) * 4, u=_t(s["u"][i]), sliding_surfaces=_t(s["s"][i]),
        flags=int(s["flags"][i]) if math.isfinite(s["flags"][i]) else 0, guidance=guidance,
        waypoint_index=int(s["waypoint"][i]) if math.isfinite(s["waypoint"][i]) else 0, mission_done=False,
        true_position=_t(s["pos_true"][i]), true_velocity=_t(s["vel"][i]),
        true_quaternion=_quat_of(s["euler_true"][i]), true_body_rates=_t(s["omega"][i]))


def mission_messages(cfg, sysid: int = 1) -> list:
    """MISSION_COUNT + MISSION_ITEM_INT (local NED) of a waypoint scenario's mission ([] otherwise)."""
    if cfg["guidance.type"] != "waypoints" or not cfg["guidance.waypoints"]:
        return []
    wps = enu_to_ned(np.asarray(cfg["guidance.waypoints"], dtype=float).reshape(-1, 3))
    radius = float(cfg["guidance.switching_radius"])
    out = [M.MAVLink_mission_count_message(target_system=255, target_component=0, count=len(wps),
                                           mission_type=M.MAV_MISSION_TYPE_MISSION)]
    for seq, (n, e, d) in enumerate(wps):
        out.append(M.MAVLink_mission_item_int_message(
            target_system=255, target_component=0, seq=seq, frame=M.MAV_FRAME_LOCAL_NED,
            command=M.MAV_CMD_NAV_WAYPOINT, current=int(seq == 0), autocontinue=1,
            param1=0.0, param2=radius, param3=0.0, param4=math.nan,
            x=int(round(n * MISSION_ITEM_LOCAL_SCALE)), y=int(round(e * MISSION_ITEM_LOCAL_SCALE)), z=float(d),
            mission_type=M.MAV_MISSION_TYPE_MISSION))
    return out


def label_messages(label: str | None) -> list:
    """STATUSTEXT (INFO) chunks naming the run (``protocol/run_label.py``: the plots' titles); [] for None."""
    if not label:
        return []
    chunks = label_chunks(label)
    msg_id = 1 if len(chunks) > 1 else 0
    return [M.MAVLink_statustext_message(severity=M.MAV_SEVERITY_INFO, text=c.encode("ascii", "replace"), id=msg_id,
                                         chunk_seq=seq) for seq, c in enumerate(chunks)]


def iter_messages(result, home: Home = DEFAULT_HOME, sysid: int = 1, label: str | None = None):
    """(simulated time s, message) of a headless run, in the order a live log would hold them;
    ``label`` (:func:`protocol.run_label.run_label`) goes first as STATUSTEXT."""
    cfg = result.config
    modes = FlightModes()
    modes.note(OFFBOARD, 0)
    ctx = TelemetryContext(rig=SimpleNamespace(cfg=cfg), home=home, sensors=load_sensor_model(), modes=modes,
                           counters=LinkCounters(), sysid=sysid, boot_unix_s=0.0)
    series = _row_lists(result.series)
    n = len(series["t"])
    guidance = cfg["guidance.type"]
    next_second = -math.inf
    other_div = max(1, int(round(float(cfg["sim.log_rate_hz"]) / OTHER_STREAMS_MAX_HZ)))
    for k in range(n):
        snap = row_snapshot(series, k, guidance, cfg["sim.physics_rate_hz"], result.control_div, result.cells_div)
        t = snap.time_s
        if k == 0:
            for msg in label_messages(label) + mission_messages(cfg, sysid):
                yield t, msg
        if t >= next_second:
            next_second = math.floor(t) + 1.0
            yield t, T.heartbeat(snap, ctx)
            yield t, P.home_position(snap, ctx)
        every = k % other_div == 0
        for name, build in ROW_STREAMS:
            if every or name in FULL_RATE_STREAMS:
                out = build(snap, ctx)
                for msg in out if isinstance(out, list) else [out]:
                    yield t, msg
        if every:
            yield t, P.sim_state(snap, ctx)


def export_tlog(result, path, home: Home = DEFAULT_HOME, sysid: int = 1, epoch_s: float = 0.0,
                label: str | None = None) -> int:
    """Write ``result`` as a .tlog at ``path`` (atomically); returns the number of messages.
    ``label`` names the run in a first STATUSTEXT (``protocol/run_label.py``).

    Record timestamps are ``epoch_s`` + simulated time (default: the Unix epoch, so the same
    run gives the same bytes).
    """
    with atomic_path(path) as tmp:
        with TlogWriter(tmp, srcSystem=sysid) as w:
            for t, msg in iter_messages(result, home, sysid, label):
                w.write(msg, epoch_s + t)
            count = w.count
    return count
