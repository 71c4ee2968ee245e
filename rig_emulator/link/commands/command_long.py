"""COMMAND_LONG / COMMAND_INT: every command is answered at once with one COMMAND_ACK.

Parameters arrive as floats; NaN means "unset" and becomes ``None`` before any handler
sees it (nothing ever casts a NaN). A handler returns a MAV_RESULT and the messages to
send to the requester after the ACK (e.g. the message MAV_CMD_REQUEST_MESSAGE asked for).
A retry (``confirmation`` > 0) or a duplicated frame of the sender's previous command is ACKed
with the previous result without acting twice (:mod:`rig_emulator.link.commands.dedup`).
Unknown commands get MAV_RESULT_UNSUPPORTED.

Supported: COMPONENT_ARM_DISARM (arming runs the pre-arm checks of
:mod:`rig_emulator.simulation.prearm` unless param2 is 21196; a refusal is DENIED with
PX4's "Arming denied: reason" STATUSTEXT), DO_SET_MODE (PX4 modes, :mod:`rig_emulator.link.commands.modes`;
a mode the rig refuses is DENIED with the reason), DO_SET_STANDARD_MODE and REQUEST_MESSAGE
for AVAILABLE_MODES (:mod:`rig_emulator.link.commands.standard_modes`), the flight commands of
:mod:`rig_emulator.link.commands.flight_commands` (NAV_TAKEOFF, NAV_LAND, NAV_RETURN_TO_LAUNCH,
DO_REPOSITION, DO_CHANGE_SPEED, DO_SET_HOME, PREFLIGHT_REBOOT_SHUTDOWN, DO_MOTOR_TEST,
DO_LAND_START), REQUEST_MESSAGE, REQUEST_AUTOPILOT_CAPABILITIES,
SET_MESSAGE_INTERVAL, GET_MESSAGE_INTERVAL, GET_HOME_POSITION, MISSION_START and
DO_SET_MISSION_CURRENT (:mod:`rig_emulator.link.mission.executor`), PREFLIGHT_CALIBRATION (param1,
gyro, or param2, magnetometer, or param5, accelerometer = 1: reruns the IMU calibration
procedure of Sec. 4-1, disarmed only and not during the identification flight),
MAV_CMD_HILMS_SHOCK, MAV_CMD_HILMS_EXTRA_MASS and
MAV_CMD_HILMS_SENSOR_FAULT (IMU modules 0..4, load cells and motors 1..4; docs/how-to/faults.md),
DO_FENCE_ENABLE (param1 0/1: the geofence off/on for this run), MAV_CMD_HILMS_SYSID (the
identification flight: :mod:`rig_emulator.link.commands.sysid_flight`).
A supported command with unusable parameters is DENIED with a STATUSTEXT saying why.
A shock outside the ranges of the config's ``disturbance.shocks`` entries (torque within
+-100 N m, duration in (0, 10] s) is DENIED with the reason; a calibration less than
:data:`CALIBRATION_INTERVAL_S` after the previous one is TEMPORARILY_REJECTED (each run
blocks the loop for about 0.1 s).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from protocol.dialect import mavlink as M
from rig_emulator.config.loader import ConfigError, check_value
from rig_emulator.config.schema import SCHEMA
from rig_emulator.link.commands import flight_commands
from rig_emulator.link.commands import standard_modes
from rig_emulator.link.commands.sysid_flight import sysid_command
from rig_emulator.link.mission.executor import MISSION_COMMANDS
from rig_emulator.link.telemetry.stream_table import ON_REQUEST, STREAMS
from rig_emulator.sensors.faults import FAULT_NAMES

ACCEPTED, DENIED, UNSUPPORTED, FAILED = (M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED,
                                         M.MAV_RESULT_UNSUPPORTED, M.MAV_RESULT_FAILED)
SHOCK_SPEC = SCHEMA["disturbance.shocks"]
CALIBRATION_INTERVAL_S = 2.0  # wall-clock seconds between two PREFLIGHT_CALIBRATION runs


def _unset_nan(value: float):
    return None if not math.isfinite(value) else float(value)


@dataclass(frozen=True)
class Command:
    command: int
    params: tuple  # 7 entries, None where unset (NaN)
    confirmation: int
    sender: tuple = (0, 0)  # (system id, component id) of the sender
    seq: int = -1  # MAVLink sequence number of the frame
    frame: int = -1  # COMMAND_INT's frame; -1 for COMMAND_LONG

    @classmethod
    def from_long(cls, msg) -> "Command":
        raw = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        return cls(msg.command, tuple(_unset_nan(p) for p in raw), msg.confirmation,
                   (msg.get_srcSystem(), msg.get_srcComponent()), msg.get_seq())

    @classmethod
    def from_int(cls, msg) -> "Command":
        raw = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x), float(msg.y), msg.z)
        return cls(msg.command, tuple(_unset_nan(p) for p in raw), 0,
                   (msg.get_srcSystem(), msg.get_srcComponent()), msg.get_seq(), msg.frame)

    def p(self, i: int):
        """Parameter ``i`` (1..7), ``None`` when unset."""
        return self.params[i - 1]

    def int_param(self, i: int):
        """Parameter ``i`` as an integer, ``None`` when unset or not a whole number."""
        v = self.params[i - 1]
        return int(v) if v is not None and v == int(v) else None


FORCE_ARM_MAGIC = 21196.0  # param2 of COMPONENT_ARM_DISARM: arm without the pre-arm checks (PX4, MAVSDK)


def _arm(cmd, srv, channel):
    flag = cmd.p(1)
    if flag not in (0.0, 1.0):
        return _denied(srv, f"arming refused: param1 {cmd.p(1)} must be 1 (arm) or 0 (disarm)")
    why = srv.flight.arm(flag == 1.0, force=cmd.p(2) == FORCE_ARM_MAGIC)
    if why is not None:
        return _denied(srv, f"Arming denied: {why}")
    srv.heartbeat_pending = True
    return ACCEPTED, []


def _set_mode(cmd, srv, channel):
    base = cmd.int_param(1)
    main = cmd.int_param(2)
    if base is None or not base & M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED or main is None:
        return _denied(srv, "mode refused: set MAV_MODE_FLAG_CUSTOM_MODE_ENABLED in param1 and PX4's main mode "
                            "in param2 (sub mode in param3)")
    return flight_commands.set_mode(srv, main, cmd.int_param(3) or 0)


def _request_message(cmd, srv, channel):
    msg_id = cmd.int_param(1)
    if msg_id == M.MAVLINK_MSG_ID_AVAILABLE_MODES:
        return standard_modes.request_available_modes(cmd, srv, channel)
    if msg_id is None or msg_id not in ON_REQUEST:
        return UNSUPPORTED, []
    return ACCEPTED, srv.build(msg_id)


def _capabilities(cmd, srv, channel):
    return ACCEPTED, srv.build(M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)


def _home(cmd, srv, channel):
    return ACCEPTED, srv.build(M.MAVLINK_MSG_ID_HOME_POSITION)


def _set_interval(cmd, srv, channel):
    msg_id, interval = cmd.int_param(1), cmd.p(2)
    if msg_id is None or msg_id not in STREAMS:
        return UNSUPPORTED, []
    if interval is None or (interval < 0 and interval != -1):
        return DENIED, []
    channel.schedule.set_interval(msg_id, interval, srv.rig.time_s)
    return ACCEPTED, []


def _get_interval(cmd, srv, channel):
    msg_id = cmd.int_param(1)
    if msg_id is None or msg_id < 0 or msg_id > 2**24 - 1:
        return DENIED, []
    interval = channel.schedule.interval_us(msg_id) if msg_id in STREAMS else 0
    return ACCEPTED, [M.MAVLink_message_interval_message(message_id=msg_id & 0xFFFF, interval_us=interval)]


def _act(srv, what: str, action, *args, done: str = "", severity: int = M.MAV_SEVERITY_INFO):
    """Run a rig action: ACCEPTED (with an optional STATUSTEXT ``done``), or DENIED with the reason."""
    try:
        action(*args)
    except ValueError as exc:
        return DENIED, srv.statustext_messages(M.MAV_SEVERITY_WARNING, f"{what} rejected: {exc}")
    return ACCEPTED, srv.statustext_messages(severity, done) if done else []


def _shock(cmd, srv, channel):
    arm, torque, duration = cmd.int_param(1), cmd.p(2), cmd.p(3)
    if arm is None or torque is None or duration is None:
        return DENIED, []
    try:  # the ranges of the config's disturbance.shocks entries (a torque of 1e30 N m made the physics NaN)
        check_value("shock", SHOCK_SPEC, [{"t": 0.0, "arm": arm, "torque": torque, "duration": duration}])
    except ConfigError as exc:
        return DENIED, srv.statustext_messages(M.MAV_SEVERITY_WARNING, f"shock rejected: {str(exc).removeprefix('shock[0].')}")
    return _act(srv, "shock", srv.rig.apply_shock, arm, torque, duration)


def _extra_mass(cmd, srv, channel):
    arm, mass, distance = cmd.int_param(1), cmd.p(2), cmd.p(3)
    if arm is None or mass is None or distance is None:
        return DENIED, []
    return _act(srv, "extra mass", srv.rig.set_extra_mass, arm, mass, distance)


def _calibration(cmd, srv, channel):
    wants = [cmd.p(i) for i in (1, 2, 5)]
    if not any(v == 1.0 for v in wants):
        # other PREFLIGHT_CALIBRATION targets (baro, radio, airspeed, ...) do not exist on the rig
        return UNSUPPORTED, []
    busy = srv.sysid_flight.busy_refusal("calibration")
    if busy is not None:  # disarmed in a swing, the rig is anything but still
        return _denied(srv, busy)
    # The procedure blocks the loop for about 0.1 s: back to back, calibrations would stall the control loop.
    now = time.monotonic()
    if now - srv.last_calibration < CALIBRATION_INTERVAL_S and not srv.snapshot().armed:  # armed: DENIED below
        return M.MAV_RESULT_TEMPORARILY_REJECTED, srv.statustext_messages(
            M.MAV_SEVERITY_WARNING, f"calibration rejected: the last one ran less than {CALIBRATION_INTERVAL_S:g} s ago")
    result, follow = _act(srv, "calibration", srv.rig.recalibrate, done="IMU calibration done (Levenberg-Marquardt)")
    if result == ACCEPTED:
        srv.last_calibration = now
    return result, follow


_DEVICES = {M.HILMS_SENSOR_KIND_IMU_MODULE: "imu", M.HILMS_SENSOR_KIND_LOAD_CELL: "load_cell",
            M.HILMS_SENSOR_KIND_MOTOR: "motor"}
_NEEDS_MAGNITUDE = ("bias", "noise", "spike", "thrust_loss")


def _denied(srv, text: str):
    return DENIED, srv.statustext_messages(M.MAV_SEVERITY_WARNING, text)


def _sensor_fault(cmd, srv, channel):
    """MAV_CMD_HILMS_SENSOR_FAULT (kind, index, fault, magnitude); HILMS_FAULT codes are
    rig_emulator.sensors.faults codes. The injection itself is announced by the fault
    reporter (to every peer, like a fault from the config)."""
    kind, index, fault = cmd.int_param(1), cmd.int_param(2), cmd.int_param(3)
    if kind is None or index is None or fault is None:
        return _denied(srv, "fault rejected: kind, index and fault (params 1-3) must be whole numbers")
    device = _DEVICES.get(kind)
    if device is None:
        return _denied(srv, f"fault rejected: kind {kind} unknown (0 IMU module, 1 load cell, 2 motor)")
    mode = FAULT_NAMES.get(fault)
    if mode is None:
        return _denied(srv, f"fault rejected: fault {fault} unknown (0..{max(FAULT_NAMES)})")
    magnitude = cmd.p(4)
    if magnitude is None and mode in _NEEDS_MAGNITUDE:
        return _denied(srv, f"fault rejected: {mode} needs a magnitude (param 4)")
    return _act(srv, "fault", srv.rig.set_fault, device, index, mode, 0.0 if magnitude is None else magnitude)


def _fence_enable(cmd, srv, channel):
    """MAV_CMD_DO_FENCE_ENABLE: param1 1 enables, 0 disables the geofence (FENCE_ENABLE, for this
    run: not stored); 2 (disable the floor only) is refused, the rig's fence has one switch."""
    flag = cmd.int_param(1)
    if flag not in (0, 1):
        return _denied(srv, f"fence enable rejected: param1 {cmd.p(1)} must be 0 (disable) or 1 (enable)")
    srv.rig.set_param("fence.enabled", bool(flag))
    srv.broadcast(srv.params.value_message(srv.params.table.by_name["FENCE_ENABLE"]))
    return ACCEPTED, srv.statustext_messages(M.MAV_SEVERITY_INFO, "fence enabled" if flag else "fence disabled")


HANDLERS = {
    M.MAV_CMD_DO_FENCE_ENABLE: _fence_enable,
    M.MAV_CMD_PREFLIGHT_CALIBRATION: _calibration,
    M.MAV_CMD_HILMS_SENSOR_FAULT: _sensor_fault,
    M.MAV_CMD_COMPONENT_ARM_DISARM: _arm,
    M.MAV_CMD_DO_SET_MODE: _set_mode,
    M.MAV_CMD_REQUEST_MESSAGE: _request_message,
    M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: _capabilities,
    M.MAV_CMD_GET_HOME_POSITION: _home,
    M.MAV_CMD_SET_MESSAGE_INTERVAL: _set_interval,
    M.MAV_CMD_GET_MESSAGE_INTERVAL: _get_interval,
    M.MAV_CMD_HILMS_SHOCK: _shock,
    M.MAV_CMD_HILMS_EXTRA_MASS: _extra_mass,
    M.MAV_CMD_HILMS_SYSID: sysid_command,
    M.MAV_CMD_DO_SET_STANDARD_MODE: standard_modes.set_standard_mode,
    **MISSION_COMMANDS,  # MISSION_START, DO_SET_MISSION_CURRENT
    **flight_commands.FLIGHT_COMMANDS,  # takeoff, land, return, reposition, speed, home, reboot, motor test
}


def execute(cmd: Command, srv, channel) -> tuple[int | None, list]:
    """Run one command for ``channel``; returns (MAV_RESULT, messages to send after the ACK).

    A retry of the sender's last command is answered with the earlier result without acting
    again; a duplicated frame or a late first transmission gets neither action nor ACK
    (result None) (:mod:`rig_emulator.link.commands.dedup`)."""
    now = time.monotonic()
    earlier = srv.command_dedup.repeat_of(cmd, channel, now)
    if earlier is not None:
        srv.counters.drop("duplicate_command")
        result, answer = earlier
        return (result if answer else None), []
    handler = HANDLERS.get(cmd.command)
    result, follow = (UNSUPPORTED, []) if handler is None else handler(cmd, srv, channel)
    srv.command_dedup.record(cmd, channel, result, now)
    return result, follow
