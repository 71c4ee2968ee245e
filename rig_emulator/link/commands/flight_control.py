"""The rig's commander: PX4's flight modes on the rig's guidance, arming with pre-arm checks,
and what happens when a flight task ends.

It owns the :class:`~rig_emulator.guidance.flight_tasks.FlightTasks` (take-off, land,
return, fly-to) and registers the mode handlers of :mod:`rig_emulator.link.commands.modes`:

* AUTO.TAKEOFF: climb at the current X/Y to MIS_TAKEOFF_ALT above home (disarmed: the climb
  starts on arming, as PX4 and QGroundControl's take-off expect), then AUTO.LOITER;
* AUTO.LOITER and POSCTL: hold the current position (POSCTL: with no stick input the rig
  flies as PX4 does with centred sticks);
* AUTO.RTL: climb to RTL_RETURN_ALT if lower, fly home, land there and disarm;
* AUTO.LAND: descend at the current X/Y, detect the landing, disarm;
* STABILIZED: hold a level attitude at the current heading (position loop off).

After a landing the rig is disarmed and the mode becomes AUTO.LOITER (arming is refused in
AUTO.RTL and AUTO.LAND, as MAVSDK expects: it switches to Hold before arming from Return).
Arming runs :func:`~rig_emulator.simulation.prearm.prearm_failure` first; a refusal comes
with the reason. A disarm command, or an arm command during one of its disarmed swings, stops the
identification flight (:mod:`rig_emulator.link.commands.sysid_flight`). MAVLink stays outside: the
command handlers in :mod:`rig_emulator.link.commands.flight_commands` call these methods and answer.
"""

from __future__ import annotations

from rig_emulator.guidance.flight_tasks import FlightTasks
from rig_emulator.link.commands import modes as MD
from rig_emulator.simulation.prearm import prearm_failure

TASK_MODES = {(MD.AUTO, MD.AUTO_TAKEOFF), (MD.AUTO, MD.AUTO_RTL), (MD.AUTO, MD.AUTO_LAND)}
NO_ARMING_IN = {(MD.AUTO, MD.AUTO_RTL): "AUTO.RTL", (MD.AUTO, MD.AUTO_LAND): "AUTO.LAND"}


class FlightControl:
    def __init__(self, server):
        self.srv = server
        self.rig = server.rig
        self.modes = server.modes
        self.tasks = FlightTasks(server.rig)
        m = self.modes
        m.register(MD.POSCTL, 0, self._hold)
        m.register(MD.AUTO, MD.AUTO_LOITER, self._hold)
        m.register(MD.STABILIZED, 0, self._stabilized)
        m.register(MD.AUTO, MD.AUTO_TAKEOFF, self._takeoff_mode)
        m.register(MD.AUTO, MD.AUTO_RTL, self._return_mode)
        m.register(MD.AUTO, MD.AUTO_LAND, self._land_mode)
        m.on_leave = self._left_mode

    # --- mode handlers (FlightModes: enter(rig) -> False refuses) --------------------------------
    def _armed(self) -> bool:
        return self.rig.armed  # now, not the chunk's snapshot: an arm command may have come in since

    def _left_mode(self, old: tuple, new: tuple) -> None:
        """A mode other than a task's own ends the task (that mode's handler set the guidance); leaving
        the identification flight's mode stops it (:mod:`rig_emulator.link.commands.sysid_flight`)."""
        if new not in TASK_MODES:
            self.tasks.cancel()
        self.srv.sysid_flight.left_mode(old, new)

    def _hold(self, rig) -> None:
        self.tasks.cancel()
        rig.hold_position()

    def _stabilized(self, rig) -> None:
        self.tasks.cancel()
        rig.set_attitude_target(0.0, 0.0, rig.heading_now())

    def _takeoff_mode(self, rig) -> None:
        self.takeoff(None)

    def _return_mode(self, rig) -> None:
        if self._armed():
            alt = self.tasks.return_home()
            self.srv.event(f"return: to home at {alt:.1f} m, then land")
        else:
            self.tasks.cancel()

    def _land_mode(self, rig) -> None:
        if self._armed():
            self.tasks.land()
            self.srv.event("landing at the current position")
        else:
            self.tasks.cancel()

    # --- what commands call ---------------------------------------------------------------------
    def takeoff(self, altitude: float | None) -> float:
        """Take off to ``altitude`` above home (None: MIS_TAKEOFF_ALT); raises ValueError."""
        armed = self._armed()
        alt = self.tasks.takeoff(altitude, armed=armed)
        self.modes.note(MD.AUTO, MD.AUTO_TAKEOFF)
        self.srv.event(f"takeoff to {alt:.1f} m" + ("" if armed else " on arming"))
        return alt

    def arm_refusal(self) -> str | None:
        """Why the rig may not arm now (pre-arm checks, mode), or None."""
        mode = NO_ARMING_IN.get((self.modes.main, self.modes.sub))
        if mode is not None:
            return f"not in {mode}: switch to AUTO.LOITER or POSCTL first"
        return prearm_failure(self.rig.snapshot(), self.rig.cfg)

    def arm(self, armed: bool, force: bool = False) -> str | None:
        """Arm (after the pre-arm checks, unless ``force``) or disarm; the refusal's reason or None."""
        if armed and not self._armed():
            why = None if force else self.arm_refusal()
            if why is not None:
                return why
            self.srv.sysid_flight.stop("armed by command")  # during a disarmed swing: the ground takes over
            if self.tasks.pending is None and (self.modes.main, self.modes.sub) in (
                    (MD.POSCTL, 0), (MD.AUTO, MD.AUTO_LOITER)):
                self.rig.hold_position()
        if not armed:
            self.srv.sysid_flight.stop("disarmed by command")
            self.tasks.cancel()
        was_armed = self.rig.armed
        self.rig.arm(armed)
        if armed and not was_armed and (self.modes.main, self.modes.sub) == (MD.AUTO, MD.AUTO_MISSION):
            self.srv.mission.armed_in_mission_mode()
        return None

    def poll(self, snapshot) -> None:
        """After each physics chunk: flight-task events and the modes they lead to
        (``snapshot()`` gives the rig's snapshot; called only while a task runs)."""
        if self.tasks.task is None and self.tasks.pending is None and not self.tasks.landing:
            return
        for ev in self.tasks.poll(snapshot()):
            if ev in ("takeoff complete", "landed"):
                self.modes.note(MD.AUTO, MD.AUTO_LOITER)
                self.srv.heartbeat_pending = True
            self.srv.event(ev + (": disarmed" if ev == "landed" else ""))

    def reset(self) -> None:
        """After a reboot: no task, home back at the origin, POSCTL."""
        self.tasks = FlightTasks(self.rig)
        self.modes.note(MD.POSCTL, 0)
