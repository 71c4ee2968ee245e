"""Checks the link runs after every chunk: the offboard set-point timeout and the geofence.

* Offboard loss (PX4's COM_OF_LOSS_T / COM_OBL_ACT, rig parameters ``offboard.loss_timeout``
  and ``offboard.loss_action``): armed in OFFBOARD, no accepted set-point for the timeout
  (simulated seconds, so it scales with the speed-up as the rig's clock does) triggers the
  action once: ``hold`` (AUTO.LOITER: hold the position), ``land`` (AUTO.LAND), ``return``
  (AUTO.RTL) or ``terminate`` (motors off, disarm).
* Geofence (FENCE_ENABLE, FENCE_RADIUS, FENCE_ALT_MAX, FENCE_ALT_MIN, FENCE_ACTION in PX4's
  GF_ACTION codes): checked at :data:`FENCE_PERIOD_S` of simulated time on the position the
  rig reports (the position its controllers fly). Going out is a breach: counted
  (FENCE_STATUS.breach_count, one per time out), reported once with a STATUSTEXT and
  FENCE_STATUS (breach status, count, type, time) and, armed, acted on: ``none``,
  ``warning`` (report only), ``hold``, ``return``, ``terminate``, ``land``. The action's
  mode stands until a mode command overrides it (as PX4 lets the operator take over) or
  the vehicle is back inside: set-points never change the mode
  (:mod:`rig_emulator.link.commands.offboard_setpoints`). Being inside again by
  :data:`FENCE_CLEAR_MARGIN_M`, whether armed or not, clears the breach ("fence: back
  inside" and FENCE_STATUS).

A mode the rig does not provide (AUTO.LAND, AUTO.RTL before they exist) falls back to
holding the position, and the STATUSTEXT says so. Each action is one readable line to
every peer.
"""

from __future__ import annotations


from dataclasses import replace

from protocol.dialect import mavlink as M
from protocol.mission_checks import MissionLimits, fence_breach
from rig_emulator.link.commands.modes import AUTO, AUTO_LAND, AUTO_LOITER, AUTO_RTL, OFFBOARD

FENCE_PERIOD_S = 0.05
#: a breach clears once the vehicle is this far inside (m): a hold made at the breach sits on the
#: boundary, and its few centimetres of hover would otherwise count as breaches again and again
FENCE_CLEAR_MARGIN_M = 0.5
_MODE_OF = {"hold": (AUTO, AUTO_LOITER), "land": (AUTO, AUTO_LAND), "return": (AUTO, AUTO_RTL)}


def mission_limits(cfg) -> MissionLimits:
    """The upload checks of :mod:`protocol.mission_checks` from the rig's parameters."""
    return MissionLimits(fence_enabled=bool(cfg["fence.enabled"]), fence_radius_m=cfg["fence.radius"],
                         fence_alt_max_m=cfg["fence.alt_max"], fence_alt_min_m=cfg["fence.alt_min"],
                         ground=bool(cfg["sim.ground"]), max_leg_m=cfg["mission.max_leg_m"])


def take_action(srv, action: str) -> str:
    """Carry out a failsafe ``action`` (hold, land, return, terminate); returns what was done."""
    rig = srv.rig
    if action == "terminate":
        rig.arm(False)
        srv.heartbeat_pending = True
        return "motors off, disarmed"
    main, sub = _MODE_OF[action]
    done = ""
    if not (srv.modes.supports(main, sub) and srv.modes.enter(main, sub, rig)):
        main, sub = _MODE_OF["hold"]
        srv.modes.enter(main, sub, rig)
        done = f"{action} not available on this rig, "
    srv.heartbeat_pending = True
    return done + f"mode {srv.modes.name}"


def _flush_heartbeat(srv) -> None:
    if srv.heartbeat_pending:
        srv.heartbeat_pending = False
        srv.broadcast_heartbeat()


class OffboardLossMonitor:
    def __init__(self, srv, setpoints):
        self.srv = srv
        self.setpoints = setpoints  # OffboardSetpoints: last_setpoint_s
        self.tripped_at: float | None = None  # set-point time the last trip was for
        self.trips = 0

    def poll(self) -> None:
        srv = self.srv
        last = self.setpoints.last_setpoint_s
        if last is None or srv.modes.main != OFFBOARD or last == self.tripped_at:
            return
        cfg = srv.rig.cfg
        timeout = cfg["offboard.loss_timeout"]
        if srv.rig.time_s - last <= timeout or not srv.snapshot().armed:
            return
        self.tripped_at = last
        self.trips += 1
        action = cfg["offboard.loss_action"]
        done = take_action(srv, action)
        srv.statustext(None, M.MAV_SEVERITY_CRITICAL,
                       f"offboard set-points lost for {timeout:g} s: {action} ({done})")
        _flush_heartbeat(srv)


class FenceMonitor:
    def __init__(self, srv):
        self.srv = srv
        self.breached: str | None = None  # why the rig is outside, None inside
        self.breach_count = 0
        self.breach_type = M.FENCE_BREACH_NONE
        self.breach_time_ms = 0
        self._next_s = 0.0

    def poll(self) -> None:
        srv = self.srv
        now = srv.rig.time_s
        if now < self._next_s:
            return
        self._next_s = now + FENCE_PERIOD_S
        cfg = srv.rig.cfg
        snap = srv.snapshot()
        limits = mission_limits(cfg)
        if self.breached is not None:
            inside = replace(limits, fence_radius_m=limits.fence_radius_m - FENCE_CLEAR_MARGIN_M,
                             fence_alt_max_m=limits.fence_alt_max_m - FENCE_CLEAR_MARGIN_M,
                             fence_alt_min_m=limits.fence_alt_min_m + FENCE_CLEAR_MARGIN_M)
            if fence_breach(snap.position, inside) is None:
                self.breached = None
                srv.statustext(None, M.MAV_SEVERITY_INFO, "fence: back inside")
                srv.broadcast(self.status_message())
            return  # still outside: the action taken stands until a mode command or back inside
        why = fence_breach(snap.position, limits)
        if why is None:
            return
        self.breached = why
        self.breach_count = (self.breach_count + 1) % 65536
        self.breach_time_ms = int(now * 1000) & 0xFFFFFFFF
        self.breach_type = (M.FENCE_BREACH_BOUNDARY if "radius" in why else
                            M.FENCE_BREACH_MAXALT if "above" in why else M.FENCE_BREACH_MINALT)
        action = cfg["fence.action"]
        if not snap.armed:
            action, done = "none", "disarmed"
        else:
            done = "no action" if action in ("none", "warning") else take_action(srv, action)
        srv.statustext(None, M.MAV_SEVERITY_CRITICAL, f"fence breach: {why}; {action} ({done})")
        srv.broadcast(self.status_message())
        _flush_heartbeat(srv)

    def status_message(self):
        return M.MAVLink_fence_status_message(
            breach_status=1 if self.breached else 0, breach_count=self.breach_count, breach_type=self.breach_type,
            breach_time=self.breach_time_ms, breach_mitigation=M.FENCE_MITIGATE_UNKNOWN)


