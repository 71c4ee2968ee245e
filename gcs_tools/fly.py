"""Ground-driven waypoint flight: the 8 cm switching of Sec. 4-4 run from the ground.

For each waypoint the tool streams position targets (SET_POSITION_TARGET_LOCAL_NED) along
the time-parameterised virtual line from where the vehicle was when the leg began to the
waypoint, and switches to the next waypoint when the vehicle's reported position
(LOCAL_POSITION_NED) is within the switching radius - with the rig's own functions
(:mod:`protocol.waypoint_switching`, compiled in
:mod:`rig_emulator.guidance.waypoint_switching`: ``leg_duration``, ``line_setpoint``,
``waypoint_reached``). Time is the vehicle's clock (``time_boot_ms`` of LOCAL_POSITION_NED),
so the run is the same at any speed-up of the rig. One set-point goes out per position
report; the vehicle holds the last one between reports.

As PX4 asks, the stream comes first: the tool sends a set-point at the vehicle's position,
then switches the vehicle to OFFBOARD (:func:`start_offboard`); set-points alone never
change a PX4 vehicle's mode. It sends the ground station's HEARTBEAT at 1 Hz throughout
(:mod:`gcs_tools.link`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from gcs_tools.errors import OperationError
from gcs_tools.link import COMMAND_TIMEOUT_S, Link
from protocol.dialect import mavlink as M
from protocol.frames import enu_to_ned, ned_to_enu
from protocol.px4_custom_mode import split_custom_mode
from rig_emulator.guidance.waypoint_switching import leg_duration, line_setpoint, waypoint_reached

POSITION_ONLY = (M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE
                 | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE | M.POSITION_TARGET_TYPEMASK_AX_IGNORE
                 | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
                 | M.POSITION_TARGET_TYPEMASK_YAW_IGNORE | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE)
DEFAULT_SPEED = 0.5  # m/s, the rig's guidance.speed
DEFAULT_MIN_LEG_TIME = 1.0  # s, the rig's guidance.min_leg_time
DEFAULT_POSITION_HZ = 20.0
NAN = math.nan
PX4_OFFBOARD = 6  # PX4's main mode OFFBOARD (custom_mode = 6 << 16)
#: how often :func:`fly` switches back to OFFBOARD after the vehicle's offboard-loss failsafe
DEFAULT_RESUMES = 3
#: what the rig's offboard-loss failsafe says (rig_emulator.link.commands.flight_monitors)
OFFBOARD_LOSS_TEXT = "offboard set-points lost"


@dataclass(frozen=True)
class Reached:
    index: int
    t_s: float  # vehicle time (time_boot_ms) when the switching condition held
    error_m: float  # distance to the waypoint then


def _position(msg) -> np.ndarray:
    return ned_to_enu([msg.x, msg.y, msg.z])


def send_target(link: Link, t_ms: int, enu) -> None:
    n, e, d = (float(v) for v in enu_to_ned(enu))
    link.mav.set_position_target_local_ned_send(t_ms, link.target_system, link.target_component,
                                                M.MAV_FRAME_LOCAL_NED, POSITION_ONLY, n, e, d,
                                                0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def start_offboard(link: Link, send_setpoint, attempts: int = 3, timeout_s: float = COMMAND_TIMEOUT_S,
                   period_s: float = 1.0 / DEFAULT_POSITION_HZ) -> None:
    """Switch the vehicle to OFFBOARD (DO_SET_MODE with PX4's custom mode 6) while streaming
    ``send_setpoint()`` before and during the wait for the answer: PX4 enters OFFBOARD only
    while a set-point stream flows, and leaves it again when the stream pauses (COM_OF_LOSS_T).

    The stream is paced on the vehicle's clock: one set-point per LOCAL_POSITION_NED received,
    so a vehicle running many times faster than real time still sees it at the position rate;
    ``period_s`` of wall time without one sends a set-point anyway. A refusal or a missing
    answer is retried; OperationError after ``attempts``."""
    result = None
    stale = link.stale_acks

    def answer_or_position(m):
        return m.get_type() == "LOCAL_POSITION_NED" or (m.command == M.MAV_CMD_DO_SET_MODE and stale.fresh(m))

    for attempt in range(attempts):
        send_setpoint()
        link.mav.command_long_send(link.target_system, link.target_component, M.MAV_CMD_DO_SET_MODE, attempt,
                                   float(M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), float(PX4_OFFBOARD),
                                   0.0, NAN, NAN, NAN, NAN)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            ack = link.recv(["COMMAND_ACK", "LOCAL_POSITION_NED"], period_s, answer_or_position)
            send_setpoint()
            if ack is None or ack.get_type() != "COMMAND_ACK":
                continue
            stale.consumed(ack)
            result = ack.result
            if result == M.MAV_RESULT_IN_PROGRESS:
                continue
            if result == M.MAV_RESULT_ACCEPTED:
                return
            break
    name = "no answer" if result is None else (
        M.enums["MAV_RESULT"][result].name if result in M.enums["MAV_RESULT"] else str(result))
    raise OperationError(f"the vehicle refused OFFBOARD ({name}) with a set-point stream flowing")


def vehicle_heartbeat(link: Link):
    """The vehicle's latest HEARTBEAT seen on the link, whatever message was waited for (None before one)."""
    hb = link.conn.messages.get("HEARTBEAT")
    if hb is None or hb.get_srcSystem() != link.target_system or hb.type == M.MAV_TYPE_GCS:
        return None
    return hb


def vehicle_mode(link: Link) -> tuple[int, int] | None:
    """(main, sub) PX4 mode of the vehicle's latest HEARTBEAT seen on the link (None before one)."""
    hb = vehicle_heartbeat(link)
    return None if hb is None else split_custom_mode(hb.custom_mode)


def fly(link: Link, points_enu, radii, speed: float = DEFAULT_SPEED, min_leg_time: float = DEFAULT_MIN_LEG_TIME,
        timeout_s: float = 600.0, link_timeout_s: float = 5.0, position_hz: float = DEFAULT_POSITION_HZ,
        arm: bool = True, report=None, resumes: int = DEFAULT_RESUMES, notice=None) -> list[Reached]:
    """Fly every waypoint in order; returns when the last is reached (OperationError on timeout/link loss).

    ``points_enu`` (N, 3) world ENU metres about the vehicle's local origin, ``radii`` (N,)
    switching radii (m), ``speed`` (m/s) and ``min_leg_time`` (s) size each virtual line.
    ``report(Reached, n)`` is called at each waypoint.

    The vehicle leaving OFFBOARD ends the flight with OperationError naming the mode it took
    and what it said (a fence breach, a mode command from another ground station), except
    after its offboard-loss failsafe ("offboard set-points lost"): the tool's own stream
    paused (a starved process, a rig far faster than real time), so the tool switches back
    to OFFBOARD, as offboard scripts do, at most ``resumes`` times, each told to
    ``notice(text)``.
    """
    pts = np.asarray(points_enu, dtype=float).reshape(-1, 3)
    radii = np.broadcast_to(np.asarray(radii, dtype=float), (pts.shape[0],))
    sp_pos, sp_vel = np.zeros(3), np.zeros(3)
    # the guidance functions run once (and compile, or load from the cache: seconds) before the
    # link is read: meanwhile the vehicle's telemetry would pile up unread, and OFFBOARD's
    # stream must not pause once it is entered
    line_setpoint(0.0, 0.0, leg_duration(0.0, 0.0, 0.0, *pts[0], speed, min_leg_time), 0.0, 0.0, 0.0, *pts[0],
                  sp_pos, sp_vel)
    waypoint_reached(0.0, 0.0, 0.0, *pts[0], radii[0])
    if link.target_system is None:
        link.wait_vehicle()
    if position_hz > 0:
        link.set_message_rate(M.MAVLINK_MSG_ID_LOCAL_POSITION_NED, position_hz)
    msg = link.recv("LOCAL_POSITION_NED", link_timeout_s)
    if msg is None:
        raise OperationError(f"no LOCAL_POSITION_NED from the vehicle within {link_timeout_s:g} s")
    if arm and not link.is_armed():
        link.arm()
    deadline = time.monotonic() + timeout_s
    reached: list[Reached] = []
    pos, t = _position(msg), msg.time_boot_ms * 1e-3
    hold = pos.copy()
    start_offboard(link, lambda: send_target(link, int(t * 1e3), hold))
    texts: list[str] = []  # the vehicle's STATUSTEXTs since OFFBOARD was entered
    in_offboard = False  # a HEARTBEAT has shown OFFBOARD since it was entered
    for i, (target, radius) in enumerate(zip(pts, radii)):
        start, t0 = pos.copy(), t
        duration = leg_duration(*start, *target, speed, min_leg_time)
        while True:
            line_setpoint(t, t0, duration, *start, *target, sp_pos, sp_vel)
            send_target(link, int(t * 1e3), sp_pos)
            if waypoint_reached(*pos, *target, radius):
                r = Reached(i, t, float(np.linalg.norm(pos - target)))
                reached.append(r)
                if report is not None:
                    report(r, pts.shape[0])
                break
            if time.monotonic() > deadline:
                raise OperationError(f"timeout after {timeout_s:g} s: waypoint {i + 1}/{pts.shape[0]} not reached "
                                     f"(error {np.linalg.norm(pos - target):.3f} m, radius {radius:g} m)")
            msg = link.recv(["LOCAL_POSITION_NED", "STATUSTEXT"], link_timeout_s)
            if msg is None:
                raise OperationError(f"link lost: no LOCAL_POSITION_NED for {link_timeout_s:g} s "
                                     f"(waypoint {i + 1}/{pts.shape[0]})")
            if msg.get_type() == "STATUSTEXT":
                texts.append(str(msg.text))
                continue
            pos, t = _position(msg), msg.time_boot_ms * 1e-3
            hb = vehicle_heartbeat(link)
            said = "".join(texts[-4:]).strip()  # a long text comes in chunks
            if in_offboard and hb is not None and not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED:
                raise OperationError(f"the vehicle disarmed at waypoint {i + 1}/{pts.shape[0]}"
                                     + (f": {said}" if said else ""))
            mode = None if hb is None else split_custom_mode(hb.custom_mode)
            if mode is None or mode[0] == PX4_OFFBOARD or not in_offboard:
                # a vehicle may say OFFBOARD only in its next HEARTBEAT after the ACK (PX4: 1 Hz)
                in_offboard = in_offboard or (mode is not None and mode[0] == PX4_OFFBOARD)
                continue
            if OFFBOARD_LOSS_TEXT in said and resumes > 0:
                resumes -= 1
                if notice is not None:
                    notice(f"the vehicle's offboard-loss failsafe took over ({said}): "
                           f"back to OFFBOARD at waypoint {i + 1}/{pts.shape[0]}")
                texts.clear()
                in_offboard = False
                # the vehicle held where it was: OFFBOARD resumes there, and the leg starts again from
                # there, not where its virtual line has got to meanwhile (a step of metres)
                hold = pos.copy()
                start_offboard(link, lambda: send_target(link, int(t * 1e3), hold))
                start, t0 = pos.copy(), t
                duration = leg_duration(*start, *target, speed, min_leg_time)
                continue
            raise OperationError(f"the vehicle left OFFBOARD for {_mode_name(link)} at waypoint "
                                 f"{i + 1}/{pts.shape[0]}" + (f": {said}" if said else ""))
    return reached


def _mode_name(link: Link) -> str:
    from pymavlink import mavutil

    return mavutil.mode_string_v10(link.conn.messages["HEARTBEAT"])


def format_reached(r: Reached, n: int, radius: float | None = None) -> str:
    extra = "" if radius is None or not math.isfinite(radius) else f", radius {radius:g} m"
    return f"waypoint {r.index + 1}/{n} reached at t = {r.t_s:.2f} s (error {r.error_m:.3f} m{extra})"
