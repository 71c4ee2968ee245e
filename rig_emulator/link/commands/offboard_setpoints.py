"""Offboard set-points (PX4's offboard interface) on the rig.

* SET_POSITION_TARGET_LOCAL_NED in LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED
  and SET_POSITION_TARGET_GLOBAL_INT in GLOBAL_INT / GLOBAL_RELATIVE_ALT_INT: position,
  velocity, acceleration, yaw and yaw rate, each component used unless its type_mask bit
  ignores it (frames and bits read in :mod:`protocol.setpoint_frames`; guidance in
  :mod:`rig_emulator.guidance.offboard`).
* SET_ATTITUDE_TARGET: the attitude quaternion (R_NED_FRD) with the collective thrust
  (``thrust`` 0..1 of the four motors' maximum; THROTTLE_IGNORE: the hover thrust), body
  rates as feed-forward; with ATTITUDE_IGNORE the body rates are tracked (rate mode), an
  ignored axis at 0 rad/s; a message that ignores attitude and rates but gives the thrust
  changes only the thrust of the attitude or rate set-point being flown (as PX4 does).
* SET_ACTUATOR_CONTROL_TARGET is refused, as by the PX4 the rig claims to be: PX4 removed
  it in v1.14 (PX4-Autopilot PR #20837, with the actuator_controls mixer groups it fed);
  PX4's direct actuator control since is uORB/ROS 2 only. The rig's own controllers always
  run here; per-motor control belongs to the lockstep simulator interface
  (HIL_ACTUATOR_CONTROLS, :mod:`rig_emulator.link.px4_simulator`), one motor disarmed to
  DO_MOTOR_TEST, body rates with collective thrust to SET_ATTITUDE_TARGET.

PX4's offboard semantics: an accepted set-point is stored and restarts the set-point
timeout (:mod:`rig_emulator.link.commands.flight_monitors`); it never changes the mode. In
OFFBOARD the rig flies each set-point as it arrives; in any other mode it only keeps the
latest. OFFBOARD is entered only by a mode command (DO_SET_MODE, SET_MODE, MAVSDK's
``offboard.start()``, MAVProxy's ``mode OFFBOARD``), and only while the stream is fresh: the
last set-point at most :data:`STREAM_MAX_AGE_S` old in simulated time (PX4's proof of life,
a stream of at least 2 Hz already flowing before the switch); otherwise the mode is refused
with the reason. Entering OFFBOARD flies the stored set-point.

A set-point the rig cannot follow is refused: counted (``counters.dropped``) and, the first
time each reason occurs on a link, reported with a STATUSTEXT saying why.
"""

from __future__ import annotations

import math

import numpy as np

from protocol.dialect import mavlink as M
from protocol.frames import T_NED_ENU, enu_to_ned, paper_euler_from_rwb
from protocol.setpoint_frames import SetpointRefused, global_setpoint, local_setpoint
from rig_emulator.link.commands.modes import OFFBOARD
from rig_emulator.physics.rotation import quat_to_rot

ATT_RATE_BITS = (M.ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE, M.ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE,
                 M.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE)
THRUST_BODY_SET = getattr(M, "ATTITUDE_TARGET_TYPEMASK_THRUST_BODY_SET", 32)
#: OFFBOARD needs a set-point at most this old (simulated seconds): a stream of 2 Hz or more (PX4)
STREAM_MAX_AGE_S = 0.5


def rwb_from_mavlink_quaternion(q) -> np.ndarray:
    """R_WB of a MAVLink attitude quaternion (w, x, y, z) of R_NED_FRD (normalised first)."""
    w, x, y, z = (float(v) for v in q)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    r = np.zeros((3, 3))
    quat_to_rot(w / n, x / n, y / n, z / n, r)
    return T_NED_ENU @ r


class OffboardSetpoints:
    """Handlers of the set-point messages for one server (``srv``: rig, modes, ctx.home,
    counters, statustext), the stored set-point, and the OFFBOARD mode's entry check."""

    def __init__(self, srv):
        self.srv = srv
        self.last_setpoint_s: float | None = None  # simulated time of the last accepted set-point
        self.accepted = 0
        self.stored: tuple | None = None  # the latest accepted set-point: (kind, arguments), see _fly
        self._reported: set = set()  # (channel id, message type, reason) already sent as STATUSTEXT
        srv.modes.register(OFFBOARD, 0, self.enter)

    # --- the OFFBOARD mode ----------------------------------------------------------------------------
    def stream_age_s(self) -> float:
        """Simulated seconds since the last accepted set-point (inf: none yet)."""
        last = self.last_setpoint_s
        return math.inf if last is None else self.srv.rig.time_s - last

    def enter(self, rig):
        """FlightModes handler of OFFBOARD: fly the stored set-point, or the reason (str) when
        the stream is not fresh (PX4: "No offboard signal")."""
        age = self.stream_age_s()
        if self.stored is None or age > STREAM_MAX_AGE_S:
            since = "no set-point received" if self.stored is None else f"last set-point {age:.1f} s ago"
            return (f"mode refused: OFFBOARD: no offboard signal ({since}); stream set-points at 2 Hz or more "
                    f"before switching")
        try:
            self._fly(self.stored)
        except ValueError as exc:
            return f"mode refused: OFFBOARD: {exc}"
        return True

    # --- outcome -------------------------------------------------------------------------------------
    def _refuse(self, msg, channel, reason: str) -> None:
        self.srv.counters.drop("setpoint_refused")
        key = (id(channel), msg.get_type(), reason)
        if key not in self._reported:
            self._reported.add(key)
            self.srv.statustext(None, M.MAV_SEVERITY_WARNING, f"{msg.get_type()} refused: {reason}")

    def _run(self, msg, channel, parse) -> None:
        """Parse a set-point message into a stored set-point; fly it at once in OFFBOARD."""
        try:
            setpoint = parse()
            if self.srv.modes.main == OFFBOARD:
                self._fly(setpoint)
        except (SetpointRefused, ValueError) as exc:
            self._refuse(msg, channel, str(exc))
            return
        self.stored = setpoint
        self.accepted += 1
        self.last_setpoint_s = self.srv.rig.time_s

    def _fly(self, setpoint) -> None:
        """Hand a stored set-point to the rig (ValueError when the rig cannot follow it)."""
        kind, args = setpoint
        rig = self.srv.rig
        if kind == "position":
            sp = args
            rig.set_offboard_setpoint(position=sp.position, velocity=sp.velocity, acceleration=sp.acceleration,
                                      yaw=sp.yaw, yaw_rate=sp.yaw_rate)
        elif kind == "attitude":
            phi, theta, psi, thrust, rates = args
            rig.set_attitude_target(phi, theta, psi, thrust_fraction=thrust, body_rates=rates)
        else:  # "rates"
            rates, thrust = args
            rig.set_body_rate_target(rates, thrust_fraction=thrust)

    # --- messages ------------------------------------------------------------------------------------------
    def position_local(self, msg, channel) -> None:
        def parse():
            position, heading = self.srv.rig.pose_now()  # where the vehicle is, as the controllers fly it
            yaw_ned = math.pi / 2.0 - heading  # paper psi -> MAVLink yaw (protocol/frames.py)
            return "position", local_setpoint(msg, enu_to_ned(position), yaw_ned)
        self._run(msg, channel, parse)

    def position_global(self, msg, channel) -> None:
        self._run(msg, channel, lambda: ("position", global_setpoint(msg, self.srv.ctx.home)))

    def attitude(self, msg, channel) -> None:
        def parse():
            mask = int(msg.type_mask)
            if mask & THRUST_BODY_SET:
                raise SetpointRefused("thrust_body (THRUST_BODY_SET) is not supported; send the collective thrust")
            thrust = None if mask & M.ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE else float(msg.thrust)
            if thrust is not None and not (math.isfinite(thrust) and 0.0 <= thrust <= 1.0):
                raise SetpointRefused(f"thrust {thrust:g} must be in [0, 1] (the rig has no reverse thrust)")
            rates_given = [not mask & b for b in ATT_RATE_BITS]
            rates = [float(v) if given else 0.0 for v, given in
                     zip((msg.body_roll_rate, msg.body_pitch_rate, msg.body_yaw_rate), rates_given)]
            if not all(math.isfinite(v) for v in rates):
                raise SetpointRefused("body rates must be finite numbers")
            if not mask & M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE:
                q = [float(v) for v in msg.q]
                norm = math.sqrt(sum(v * v for v in q)) if all(math.isfinite(v) for v in q) else math.nan
                if not 0.5 < norm < 1.5:
                    raise SetpointRefused(f"attitude quaternion norm {norm:.3g} is not ~1")
                phi, theta, psi = paper_euler_from_rwb(rwb_from_mavlink_quaternion(q))
                return "attitude", (phi, theta, psi, thrust, rates if any(rates_given) else None)
            if any(rates_given):
                return "rates", (rates, thrust)
            if thrust is not None:  # only the thrust of the attitude or rate set-point being flown changes
                if self.stored is None or self.stored[0] == "position":
                    raise SetpointRefused("a thrust alone needs an attitude or body-rate set-point to go with")
                kind, args = self.stored
                return kind, (*args[:3], thrust, args[4]) if kind == "attitude" else (args[0], thrust)
            raise SetpointRefused("type_mask ignores attitude, body rates and thrust: nothing to follow")
        self._run(msg, channel, parse)

    def actuator_control(self, msg, channel) -> None:
        self._refuse(msg, channel, "actuator-level control is not supported (removed from PX4 in v1.14; the rig's "
                                   "controllers always run): send SET_ATTITUDE_TARGET body rates and thrust, or fly "
                                   "the motors through the lockstep simulator interface")

    def handlers(self) -> dict:
        return {
            "SET_POSITION_TARGET_LOCAL_NED": self.position_local,
            "SET_POSITION_TARGET_GLOBAL_INT": self.position_global,
            "SET_ATTITUDE_TARGET": self.attitude,
            "SET_ACTUATOR_CONTROL_TARGET": self.actuator_control,
        }
