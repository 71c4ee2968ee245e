"""The standard flight commands, with PX4's semantics (COMMAND_LONG and COMMAND_INT).

Each handler turns the command into a call on :class:`~rig_emulator.link.commands.flight_control.FlightControl`
or the rig and answers ``(MAV_RESULT, messages after the ACK)``; a refusal always comes with
a STATUSTEXT saying why. Positions: global frames become the rig's world ENU about the
local origin (``--home``) with :mod:`protocol.geodesy`; the virtual ground is flat at the
origin's altitude, so a relative or terrain altitude is the height above it.

* ``MAV_CMD_NAV_TAKEOFF``: param7 the altitude, AMSL for COMMAND_LONG and MAV_FRAME_GLOBAL
  (as PX4 reads it), above home for the relative and terrain frames of COMMAND_INT; NaN =
  MIS_TAKEOFF_ALT. Lower than MIS_TAKEOFF_ALT above home: MIS_TAKEOFF_ALT, with PX4's
  "Using minimum takeoff altitude" warning. Accepted while disarmed (the climb starts on
  arming). Latitude, longitude and yaw are not used (the rig takes off where it is).
* ``MAV_CMD_NAV_LAND``: AUTO.LAND (land where the rig is; latitude/longitude not used).
* ``MAV_CMD_NAV_RETURN_TO_LAUNCH``: AUTO.RTL.
* ``MAV_CMD_DO_REPOSITION`` (MAVSDK's goto_location, QGroundControl's "go to location" and
  pause, MAVProxy's guided): param1 ground speed (m/s, -1/NaN = cruise), param2 flag
  MAV_DO_REPOSITION_FLAGS_CHANGE_MODE (required, as PX4: the rig goes to AUTO.LOITER);
  latitude, longitude, altitude NaN (or 0/0 for the position in COMMAND_INT) = keep the
  current one. Armed only.
* ``MAV_CMD_DO_CHANGE_SPEED``: param2 speed (m/s; -1 no change, -2 back to the default) of
  the legs flown from now on and of the leg being flown; param1 (speed type) not used.
* ``MAV_CMD_DO_SET_HOME``: param1 = 1 home at the current position, else at latitude,
  longitude (within 10 km); the altitude stays on the virtual ground (a different altitude
  is reported in a STATUSTEXT and not used). Return flies there.
* ``MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN``: param1 = 1 (reboot the autopilot) restarts the
  simulation from its initial state, disarmed, with the parameters and the mission kept,
  without restarting the process; param1 = 0 with other params: nothing (ACCEPTED, as the
  spec's "do nothing"); shutdown (2) and other values are refused. Disarmed only, and not while the
  identification flight runs (disarmed in its swings).
* ``MAV_CMD_DO_MOTOR_TEST``: param1 motor 1..4, param2 throttle type (0 percent, 1 PWM,
  2 pass-through: fraction of full voltage), param3 value, param4 timeout (s, <= 10): spins
  one motor at that voltage on the bench, disarmed only (and not during the identification
  flight's swings); param5 motor count 0/1.
* ``MAV_CMD_DO_SET_STANDARD_MODE`` and ``MAV_CMD_DO_LAND_START``: see
  :mod:`rig_emulator.link.commands.standard_modes` and :func:`_land_start`.
"""

from __future__ import annotations

import math

from protocol.dialect import mavlink as M
from protocol.geodesy import global_to_local_enu
from rig_emulator.link.commands import modes as MD

ACCEPTED, DENIED, UNSUPPORTED, FAILED = (M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED,
                                         M.MAV_RESULT_UNSUPPORTED, M.MAV_RESULT_FAILED)
RELATIVE_FRAMES = {M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                   M.MAV_FRAME_GLOBAL_TERRAIN_ALT, M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT}
AMSL_FRAMES = {M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_INT}
MAX_HOME_SHIFT_M = 10_000.0
MOTOR_TEST_MAX_S = 10.0


def refuse(srv, text: str, result: int = DENIED):
    return result, srv.statustext_messages(M.MAV_SEVERITY_WARNING, text)


def _frame(cmd) -> int:
    """The frame of a COMMAND_INT; COMMAND_LONG positions are AMSL (MAV_FRAME_GLOBAL)."""
    frame = getattr(cmd, "frame", None)
    return M.MAV_FRAME_GLOBAL if frame is None or frame < 0 else frame


def _height_above_ground(srv, cmd, z) -> float | None:
    """param7/z as a height above the virtual ground (home altitude), by frame; None: unknown frame."""
    frame = _frame(cmd)
    if frame in RELATIVE_FRAMES:
        return float(z)
    if frame in AMSL_FRAMES:
        return float(z) - srv.ctx.home.alt_m
    return None


def _position_enu(srv, cmd, lat, lon, alt):
    """World ENU of a global position (lat/lon in degrees, alt by frame), each part None = unset."""
    here = srv.rig.position_now()
    out = here.copy()
    if lat is not None and lon is not None:
        enu = global_to_local_enu(srv.ctx.home, lat, lon, srv.ctx.home.alt_m)
        out[0], out[1] = enu[0], enu[1]
    if alt is not None:
        h = _height_above_ground(srv, cmd, alt)
        if h is None:
            return None
        out[2] = h
    return out


def _latlon(cmd) -> tuple:
    """(lat, lon) in degrees from params 5/6 (COMMAND_INT: 1e7 integers), None when unset."""
    x, y = cmd.p(5), cmd.p(6)
    if x is None or y is None:
        return None, None
    if getattr(cmd, "frame", None) is not None and cmd.frame >= 0:  # COMMAND_INT
        if x == 0 and y == 0:
            return None, None
        x, y = x / 1e7, y / 1e7
    if not (-90.0 <= x <= 90.0 and -180.0 <= y <= 180.0):
        raise ValueError(f"latitude {x:g} / longitude {y:g} out of range")
    return x, y


def set_mode(srv, main: int, sub: int):
    """Enter (main, sub) as DO_SET_MODE does: (result, follow)."""
    modes = srv.modes
    if not modes.supports(main, sub):
        return refuse(srv, f"mode refused: {modes.refusal(main, sub)}")
    if not modes.enter(main, sub, srv.rig):
        return refuse(srv, modes.last_refusal)
    srv.heartbeat_pending = True
    return ACCEPTED, []


def takeoff(cmd, srv, channel):
    z = cmd.p(7)
    min_alt = srv.flight.tasks.takeoff_altitude
    alt = None
    follow = []
    if z is not None:
        alt = _height_above_ground(srv, cmd, z)
        if alt is None:
            return refuse(srv, f"takeoff refused: frame {_frame(cmd)} not supported (global frames only)",
                          UNSUPPORTED)
        if alt < min_alt:
            follow = srv.statustext_messages(
                M.MAV_SEVERITY_WARNING, f"Using minimum takeoff altitude: {min_alt:.2f} m (param7 {z:g} is "
                f"{alt:.1f} m above home; PX4 reads it as AMSL)")
            alt = None
    try:
        srv.flight.takeoff(alt)
    except ValueError as exc:
        return refuse(srv, f"takeoff refused: {exc}")
    srv.heartbeat_pending = True
    return ACCEPTED, follow


def land(cmd, srv, channel):
    return set_mode(srv, MD.AUTO, MD.AUTO_LAND)


def return_to_launch(cmd, srv, channel):
    return set_mode(srv, MD.AUTO, MD.AUTO_RTL)


def reposition(cmd, srv, channel):
    flags = cmd.int_param(2)
    if flags is None or not flags & M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE:
        return refuse(srv, "reposition refused: set MAV_DO_REPOSITION_FLAGS_CHANGE_MODE (param2 = 1), as PX4 needs")
    if not srv.rig.armed:
        return refuse(srv, "reposition refused: arm and take off first", M.MAV_RESULT_TEMPORARILY_REJECTED)
    speed = cmd.p(1)
    if speed is not None and speed <= 0.0:
        speed = None
    try:
        lat, lon = _latlon(cmd)
    except ValueError as exc:
        return refuse(srv, f"reposition refused: {exc}")
    target = _position_enu(srv, cmd, lat, lon, cmd.p(7))
    if target is None:
        return refuse(srv, f"reposition refused: frame {_frame(cmd)} not supported (global frames only)",
                      UNSUPPORTED)
    if target[2] < 0.0:
        return refuse(srv, f"reposition refused: target {target[2]:.2f} m below the ground")
    srv.modes.note(MD.AUTO, MD.AUTO_LOITER)  # first: entering a mode ends a task, this one starts after
    srv.flight.tasks.goto(target, speed)
    srv.heartbeat_pending = True
    e, n, u = (float(v) for v in target)
    srv.event(f"reposition to E {e:.2f} N {n:.2f} U {u:.2f} m")
    return ACCEPTED, []


def change_speed(cmd, srv, channel):
    v = cmd.p(2)
    if v is None or v == -1.0:
        return ACCEPTED, []
    try:
        srv.rig.change_speed(None if v == -2.0 else v)
    except ValueError as exc:
        return refuse(srv, f"change speed refused: {exc}")
    limit = srv.rig.cfg["guidance.max_speed"]
    capped = f" (limited to MPC_XY_VEL_MAX {limit:g} m/s)" if v != -2.0 and v > limit else ""
    srv.event(f"cruise speed {'default' if v == -2.0 else f'{v:g} m/s'}{capped}")
    return ACCEPTED, []


def set_home(cmd, srv, channel):
    if cmd.p(1) == 1.0:
        pos = srv.rig.position_now()
        note = ""
    else:
        try:
            lat, lon = _latlon(cmd)
        except ValueError as exc:
            return refuse(srv, f"set home refused: {exc}")
        if lat is None:
            return refuse(srv, "set home refused: latitude and longitude needed (or param1 = 1)")
        pos = global_to_local_enu(srv.ctx.home, lat, lon, srv.ctx.home.alt_m)
        if math.hypot(pos[0], pos[1]) > MAX_HOME_SHIFT_M:
            return refuse(srv, f"set home refused: {math.hypot(pos[0], pos[1]) / 1000:.0f} km from the rig's origin "
                               f"(at most {MAX_HOME_SHIFT_M / 1000:g} km)")
        alt = cmd.p(7)
        h = None if alt is None else _height_above_ground(srv, cmd, alt)
        note = "" if h is None or abs(h) < 0.5 else f" (altitude kept on the virtual ground, not {h:.1f} m)"
    srv.flight.tasks.set_home(pos)
    hx, hy = srv.flight.tasks.home[:2]
    text = f"home set at E {hx:.2f} N {hy:.2f} m{note}"
    srv.event(text)
    return ACCEPTED, srv.build(M.MAVLINK_MSG_ID_HOME_POSITION) + srv.statustext_messages(M.MAV_SEVERITY_INFO, text)


def reboot(cmd, srv, channel):
    what = cmd.p(1)
    if what in (None, 0.0):
        return ACCEPTED, []
    if what != 1.0:
        return refuse(srv, f"reboot refused: param1 {what:g} (only 1, reboot the autopilot, is supported)",
                      UNSUPPORTED)
    if srv.rig.armed:
        return refuse(srv, "reboot refused: disarm first")
    busy = srv.sysid_flight.busy_refusal("reboot")
    if busy is not None:
        return refuse(srv, busy)
    srv.reboot_pending = True  # the server reboots once the ACK is out
    return ACCEPTED, []


def motor_test(cmd, srv, channel):
    motor, kind, value, timeout = cmd.int_param(1), cmd.int_param(2), cmd.p(3), cmd.p(4)
    if srv.rig.armed:
        return refuse(srv, "motor test refused: disarm first")
    busy = srv.sysid_flight.busy_refusal("motor test")
    if busy is not None:
        return refuse(srv, busy)
    if motor is None or not 1 <= motor <= 4:
        return refuse(srv, f"motor test refused: motor {cmd.p(1)} must be 1..4")
    if value is None or timeout is None or not 0.0 < timeout <= MOTOR_TEST_MAX_S:
        return refuse(srv, f"motor test refused: timeout (param4) must be in (0, {MOTOR_TEST_MAX_S:g}] s")
    if kind == M.MOTOR_TEST_THROTTLE_PERCENT:
        fraction = value / 100.0
    elif kind == M.MOTOR_TEST_THROTTLE_PWM:
        fraction = (value - 1000.0) / 1000.0
    elif kind == M.MOTOR_TEST_THROTTLE_PILOT:
        return refuse(srv, "motor test refused: the rig has no pilot throttle (RC)", UNSUPPORTED)
    else:
        fraction = value
    if not 0.0 <= fraction <= 1.0:
        return refuse(srv, f"motor test refused: throttle {value:g} outside its range")
    try:
        volts = srv.rig.motor_test(motor, fraction, timeout)
    except ValueError as exc:
        return refuse(srv, f"motor test refused: {exc}")
    srv.event(f"motor test: motor {motor} at {volts:.1f} V for {timeout:g} s")
    return ACCEPTED, []


def land_start(cmd, srv, channel):
    """DO_LAND_START (MAVProxy's ``land``): the rig's missions have no landing-sequence marker,
    so there is no landing sequence to jump to (PX4 refuses likewise)."""
    return refuse(srv, "land start refused: no DO_LAND_START landing sequence in the mission; "
                       "land here with NAV_LAND (mode LAND)", FAILED)


FLIGHT_COMMANDS = {
    M.MAV_CMD_NAV_TAKEOFF: takeoff,
    M.MAV_CMD_NAV_LAND: land,
    M.MAV_CMD_NAV_RETURN_TO_LAUNCH: return_to_launch,
    M.MAV_CMD_DO_REPOSITION: reposition,
    M.MAV_CMD_DO_CHANGE_SPEED: change_speed,
    M.MAV_CMD_DO_SET_HOME: set_home,
    M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN: reboot,
    M.MAV_CMD_DO_MOTOR_TEST: motor_test,
    M.MAV_CMD_DO_LAND_START: land_start,
}
