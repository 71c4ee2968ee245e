"""The stored mission and its execution: start, pause/resume, set current, progress reports.

The mission is a tuple of :class:`protocol.mission_items.MissionItem` (what a download
returns) and the :class:`~protocol.mission_items.MissionPlan` the rig flies, built about the
rig's home; :mod:`rig_emulator.link.mission.transfer` replaces both at once when an upload
completes (:meth:`MissionExecutor.replace`). The guidance is the compiled waypoint runner
with the Sec. 4-4 switching of ``protocol.waypoint_switching`` (the headless runner's).

Starting and stopping (PX4's interface, which MAVSDK and QGroundControl use):

* ``MAV_CMD_MISSION_START`` (param1 first item, param2 last item; unset, 0 or a last item
  before the first = to the end): flies from the first navigation item at or after
  ``first``; the mission ends at ``last``. The rig must be armed and hold a mission
  (MAV_RESULT_DENIED otherwise, with a STATUSTEXT saying why).
* ``MAV_CMD_DO_SET_MODE`` to AUTO.MISSION (PX4 custom mode 4/4, what MAVSDK's
  ``start_mission`` sends): starts a mission not started yet from the current item,
  resumes a paused one from its current item on a new virtual line from where the rig is;
  a completed mission stays complete (restart it with MISSION_START or a new current item).
  Disarmed, the mode is taken and the mission starts when the rig is armed (PX4; what
  QGroundControl's "start mission" expects). Refused (MAV_RESULT_DENIED) without a mission.
* The legs end: a NAV_RETURN_TO_LAUNCH item hands over to AUTO.RTL (return, land, disarm); a
  mission ending in NAV_LAND disarms once the land detector finds the rig on the ground; a
  final MAV_CMD_HILMS_SYSID item flies the identification flight in AUTO.MISSION
  (:mod:`rig_emulator.link.commands.sysid_flight`; MISSION_CURRENT shows its seq): when its
  programme has been flown the rig is disarmed in AUTO.LOITER, MISSION_ITEM_REACHED names the item
  and the mission is complete; stopped before its end (a mode change, a disarm, an abort), the
  mission is paused at the item, and resuming it flies the programme again from its start.
* Leaving AUTO.MISSION (AUTO.LOITER, POSCTL, OFFBOARD, ...) pauses: the rig holds where it
  is (the mode's own behaviour; if a mode would keep the mission running, the rig holds).
* ``MAV_CMD_DO_SET_MISSION_CURRENT`` (param1 seq; param2 is not used) and the older
  MISSION_SET_CURRENT: flying, the rig turns to that item at once; otherwise it becomes
  the item the next start or resume flies to. A non-navigation item stands for the first
  navigation item after it. Out of range: DENIED (the message form is answered with
  MISSION_CURRENT in both cases, as the protocol asks).

A new mission replaces the old one atomically; if the old one was being flown, or was
finished and the armed rig holds its end in AUTO.MISSION, the new one is flown from its first
item at once (PX4's navigator does the same: MissionBase::onMissionUpdate sets the new items
while the mission mode is active, finished or not). Clearing the mission while flying holds
position.
With a ``store`` (:mod:`rig_emulator.link.mission.store`) the new mission (or the cleared
one) is stored first; when it cannot be, nothing changes and :meth:`MissionExecutor.replace`
raises :class:`~rig_emulator.link.state.directory.StateWriteError`.

Reports: MISSION_ITEM_REACHED (to every peer) each time a navigation item is reached (the
switching radius test), MISSION_CURRENT on every change of item, state or mode and as a
stream. MISSION_CURRENT carries ``total`` (items excluding a home item 0, UINT16_MAX
without a mission) and ``mission_state`` (MISSION_STATE: 1 no mission, 2 not started,
3 active, 4 paused, 5 complete); ``seq`` is the item being flown (the last one once
complete).
"""

from __future__ import annotations

import math

import numpy as np

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionPlan, mission_plan  # noqa: F401 - MissionPlan: the executor's type
from dataclasses import replace as dc_replace

from rig_emulator.link.commands.modes import AUTO, AUTO_LOITER, AUTO_MISSION, AUTO_RTL

ACCEPTED, DENIED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED
UINT16_MAX = 65535
NO_MISSION, NOT_STARTED, ACTIVE, PAUSED, COMPLETE = (
    M.MISSION_STATE_NO_MISSION, M.MISSION_STATE_NOT_STARTED, M.MISSION_STATE_ACTIVE, M.MISSION_STATE_PAUSED,
    M.MISSION_STATE_COMPLETE)
ITEM0_HOME_KEY = "mission.item0_home"


class MissionExecutor:
    def __init__(self, server, store=None):
        self.srv = server
        self.store = store  # save(items, home) before a change, or None
        self.rig = server.rig
        self.modes = server.modes
        self.items: tuple = ()
        self.plan: MissionPlan | None = None
        self.state = NO_MISSION
        self.current_seq = 0  # the item to fly next when not flying
        self._nav = 0  # waypoint index of the flown plan
        self._flown: MissionPlan | None = None  # the plan (maybe cut at a last item) being flown
        self._reported_t = np.zeros(0)
        self._announced = None
        self._at_sysid = False  # the flown plan has reached its MAV_CMD_HILMS_SYSID item
        self.reached_count = 0
        self.modes.register(AUTO, AUTO_MISSION, self._enter_mission_mode)

    # --- the stored mission ---------------------------------------------------------------
    @property
    def item0_home(self) -> bool:
        return bool(self.rig.cfg[ITEM0_HOME_KEY])

    def _plan(self) -> MissionPlan:
        """The plan of the stored items under the current item-0 convention."""
        if self.plan is None or self.plan.first_seq != int(self.item0_home):
            self.plan = mission_plan(self.items, self.srv.ctx.home, self.item0_home)
        return self.plan

    def replace(self, items, persist: bool = True) -> None:
        """Store ``items`` (validated) as the mission; raises ValueError (nothing changes)."""
        items = tuple(items)
        plan = mission_plan(items, self.srv.ctx.home, self.item0_home)
        if persist and self.store is not None:
            self.store.save(items, self.srv.ctx.home)
        was_active = self.state == ACTIVE or (
            self.state == COMPLETE and self.rig.armed and (self.modes.main, self.modes.sub) == (AUTO, AUTO_MISSION))
        self.items, self.plan = items, plan
        self.current_seq = plan.first_seq if plan.count > plan.first_seq else 0
        if not items:
            self.state = NO_MISSION
            if was_active:
                self._hold()
        elif was_active:
            if plan.size or plan.sysid_seq >= 0:
                self._fly(plan, 0 if plan.size else None, keep_reached=False)
            else:
                self._hold()
                self.state = COMPLETE
        else:
            self.state = NOT_STARTED
        self.announce()

    def clear(self) -> None:
        self.replace(())

    def _hold(self) -> None:
        self._end_sysid("the mission was replaced")
        self.rig.hold_position()
        self._flown = None
        if (self.modes.main, self.modes.sub) == (AUTO, AUTO_MISSION):
            self.modes.note(AUTO, AUTO_LOITER)
            self.srv.heartbeat_pending = True

    def _fly(self, plan: MissionPlan, index: int | None, keep_reached: bool) -> None:
        """Fly ``plan`` from waypoint ``index``; None: no waypoint is left, straight to its sysid item."""
        self._end_sysid("the mission moved on")
        if index is None:
            self._flown, self._nav = plan, max(plan.size - 1, 0)
            self.state = ACTIVE
            if not self._start_sysid():
                return
            if (self.modes.main, self.modes.sub) != (AUTO, AUTO_MISSION):
                self.modes.note(AUTO, AUTO_MISSION)
                self.srv.heartbeat_pending = True
            return
        if self._flown is not plan or not keep_reached:
            self.rig.set_mission(plan.waypoints, plan.radii, plan.holds, plan.speeds, plan.free_xy)
            self._reported_t = np.full(plan.size, np.nan)
            keep_reached = False
        self.rig.start_mission(index, keep_reached=keep_reached)
        self._flown, self._nav = plan, index
        self.state = ACTIVE
        if (self.modes.main, self.modes.sub) != (AUTO, AUTO_MISSION):
            self.modes.note(AUTO, AUTO_MISSION)
            self.srv.heartbeat_pending = True

    def _why_not(self, armed_needed: bool = True) -> str | None:
        if armed_needed and not self.rig.armed:
            return "mission refused: arm first"
        if not self.items:
            return "mission refused: no mission (or no navigation item) stored"
        plan = self._plan()
        if not (plan.size or plan.return_seq >= 0 or plan.sysid_seq >= 0):
            return "mission refused: no mission (or no navigation item) stored"
        return None

    def after_reboot(self) -> None:
        """A reboot restarted the simulation: the stored mission stays, not started."""
        self._flown = None
        self._at_sysid = False
        self._nav = 0
        self.state = NOT_STARTED if self.items else NO_MISSION
        self.current_seq = self._plan().first_seq if self.items and self._plan().count > self._plan().first_seq else 0
        self.announce()

    def _finish(self) -> None:
        """The last leg is done: a NAV_RETURN_TO_LAUNCH item returns (AUTO.RTL), a final
        NAV_LAND disarms once the land detector finds the rig on the ground."""
        plan = self._flown
        if plan is None:
            return
        if plan.return_seq >= 0:
            self.srv.event(f"mission: item {plan.return_seq} NAV_RETURN_TO_LAUNCH, returning")
            self.modes.enter(AUTO, AUTO_RTL, self.rig)
            self.srv.heartbeat_pending = True
        elif plan.size and plan.lands.shape[0] == plan.size and plan.lands[-1]:
            self.srv.flight.tasks.watch_landing()

    # --- the identification flight item ------------------------------------------------------------
    def _start_sysid(self) -> bool:
        """The flown plan reached its MAV_CMD_HILMS_SYSID item: fly the programme for the mission (one
        flown in AUTO.SYSID goes on, now the mission's). False, with the reason said and the mission
        paused, when it cannot start."""
        self._at_sysid = True
        seq = self._flown.sysid_seq
        why = self.srv.sysid_flight.start_for_mission(seq)
        if why is None:
            return True
        self.srv.statustext(None, M.MAV_SEVERITY_WARNING, f"mission: item {seq}: {why}")
        self.state = PAUSED
        self.rig.hold_position()
        if (self.modes.main, self.modes.sub) == (AUTO, AUTO_MISSION):
            self.modes.note(AUTO, AUTO_LOITER)
            self.srv.heartbeat_pending = True
        return False

    def _end_sysid(self, reason: str) -> None:
        """Stop a programme flown for this mission (the mission steers next)."""
        if self._at_sysid:
            self._at_sysid = False
            if self.srv.sysid_flight.owner == "mission":
                self.srv.sysid_flight.stop(reason, hold=False)

    def sysid_ended(self, done: bool) -> None:
        """The programme flown for the mission ended: flown to its end (the mission is complete) or
        stopped (the mission is paused at the item)."""
        if not self._at_sysid or self._flown is None:
            return
        if done:
            self.state = COMPLETE
            self.srv.broadcast(M.MAVLink_mission_item_reached_message(seq=self._flown.sysid_seq))
            self.reached_count += 1
        else:
            self.state = PAUSED
        self.announce()

    def _refuse(self, reason: str) -> tuple[int, list]:
        return DENIED, self.srv.statustext_messages(M.MAV_SEVERITY_WARNING, reason)

    # --- commands -----------------------------------------------------------------------------
    def start(self, first, last) -> tuple[int, list]:
        """MAV_CMD_MISSION_START: (MAV_RESULT, messages to follow the ACK)."""
        why = self._why_not()
        if why is not None:
            return self._refuse(why)
        plan = self._plan()
        n = plan.count
        for name, v in (("first", first), ("last", last)):
            if v is not None and (v != int(v) or not 0 <= v < n):
                return self._refuse(f"mission refused: {name} item {v:g} not in 0..{n - 1}")
        first = plan.first_seq if first is None else max(int(first), plan.first_seq)
        last = n - 1 if last is None or last == 0 or last < first else int(last)
        if last < n - 1:
            keep = [i for i, s in enumerate(plan.seqs) if s <= last]
            plan = dc_replace(plan, waypoints=plan.waypoints[keep], radii=plan.radii[keep], holds=plan.holds[keep],
                              speeds=plan.speeds[keep], free_xy=plan.free_xy[keep], lands=plan.lands[keep],
                              horizontal_m=plan.horizontal_m[keep] if plan.horizontal_m.size else plan.horizontal_m,
                              seqs=tuple(plan.seqs[i] for i in keep),
                              return_seq=plan.return_seq if plan.return_seq <= last else -1,
                              sysid_seq=plan.sysid_seq if plan.sysid_seq <= last else -1)
        index = plan.nav_index(first)
        if index is None:
            if plan.return_seq >= first:  # nothing to fly before the return
                self._flown, self.state = plan, COMPLETE
                self._finish()
                self.announce()
                return ACCEPTED, []
            if plan.sysid_seq >= first:  # nothing to fly before the identification flight
                self._fly(plan, None, keep_reached=False)
                self.announce()
                return ACCEPTED, []
            return self._refuse(f"mission refused: no navigation item in {first}..{last}")
        self._fly(plan, index, keep_reached=False)
        self.announce()
        return ACCEPTED, []

    def set_current(self, seq) -> tuple[int, list]:
        """DO_SET_MISSION_CURRENT / MISSION_SET_CURRENT: (MAV_RESULT, messages)."""
        if not self.items:
            return self._refuse("set current refused: no mission stored")
        plan = self._plan()
        if seq is None or seq != int(seq) or not 0 <= seq < plan.count:
            return self._refuse(f"set current refused: item {seq} not in 0..{plan.count - 1}")
        seq = max(int(seq), plan.first_seq)
        if self.state == ACTIVE and self._flown is not None:
            index = self._flown.nav_index(seq)
            if index is None and self._flown.sysid_seq < seq:
                return self._refuse(f"set current refused: no navigation item from {seq} on")
            self._fly(self._flown, index, keep_reached=True)
        else:
            self.current_seq = seq
            if self.state == PAUSED:
                self._flown = None  # resume from the new item on the whole mission
            elif self.state == COMPLETE:
                self.state = NOT_STARTED
        self.announce()
        return ACCEPTED, []

    def _enter_mission_mode(self, rig) -> bool:
        """FlightModes handler of AUTO.MISSION: False refuses the mode. Disarmed with a
        mission, the mode is taken and the mission starts on arming (PX4; QGroundControl's
        "start mission" switches to Mission first, then arms)."""
        why = self._why_not(armed_needed=False)
        if why is not None:
            return why
        if not self.rig.armed:
            return True
        return self._fly_from_mode()

    def armed_in_mission_mode(self) -> None:
        """The rig was armed in AUTO.MISSION: fly (FlightControl.arm calls this)."""
        outcome = self._fly_from_mode()
        if outcome is not True:
            self.srv.statustext(None, M.MAV_SEVERITY_WARNING, str(outcome))
            self.modes.note(AUTO, AUTO_LOITER)
            self.rig.hold_position()
            self.srv.heartbeat_pending = True
        self.announce()

    def _fly_from_mode(self) -> bool | str:
        """Fly (or resume) from AUTO.MISSION; the reason when there is nothing to fly."""
        if self.state == ACTIVE:
            return True
        if self.state == COMPLETE:
            self.rig.hold_position()
            return True
        if self.state == PAUSED and self._flown is not None:
            self._fly(self._flown, None if self._at_sysid else self._nav, keep_reached=True)
        else:
            plan = self._plan()
            index = plan.nav_index(self.current_seq)
            if index is None and plan.sysid_seq < self.current_seq:
                return "mission refused: no navigation item left"
            self._fly(plan, index, keep_reached=False)
        return True

    # --- progress ---------------------------------------------------------------------------------
    def poll(self) -> None:
        """After each physics chunk: reached items, completion, pauses; MISSION_CURRENT on change."""
        if self.state == ACTIVE:
            if (self.modes.main, self.modes.sub) != (AUTO, AUTO_MISSION):
                if self.rig.mission_status().flying:
                    self.rig.hold_position()  # a mode that kept the mission target: hold instead
                self.state = PAUSED
            elif not self._at_sysid:  # (the identification flight's progress: sysid_ended)
                st = self.rig.mission_status()
                self._report_reached(st.reached_t)
                self._nav = st.index
                if st.done and self._flown is not None and self._flown.sysid_seq >= 0:
                    self._start_sysid()
                elif st.done:
                    self.state = COMPLETE
                    self._finish()
        self.announce()

    def _report_reached(self, reached_t: np.ndarray) -> None:
        if self._flown is None or reached_t.shape != self._reported_t.shape:
            return
        new = np.isfinite(reached_t) & ~(reached_t == self._reported_t)
        if not new.any():
            return
        for i in np.flatnonzero(new):
            self.srv.broadcast(M.MAVLink_mission_item_reached_message(seq=self._flown.seqs[i]))
            self.srv.console.line(self.rig.time_s, f"mission: reached item {self._flown.seqs[i]}")
            self.reached_count += 1
        self._reported_t = reached_t.copy()

    def current_seq_now(self) -> int:
        if self._at_sysid and self._flown is not None:
            return self._flown.sysid_seq
        if self.state in (ACTIVE, PAUSED, COMPLETE) and self._flown is not None and self._flown.size:
            return self._flown.seqs[min(self._nav, self._flown.size - 1)]
        return self.current_seq

    def _current_fields(self) -> tuple:
        """(seq, total, mission_state, mission_mode) of MISSION_CURRENT now."""
        if not self.items:
            total = UINT16_MAX
        else:
            total = len(self.items) - (1 if self.item0_home else 0)
        in_mode = (self.modes.main, self.modes.sub) == (AUTO, AUTO_MISSION)
        mode = 0 if not self.items else (1 if in_mode else 2)
        return self.current_seq_now(), total, self.state, mode

    def current_message(self):
        """MISSION_CURRENT for the present state."""
        seq, total, state, mode = self._current_fields()
        return M.MAVLink_mission_current_message(seq=seq, total=total, mission_state=state, mission_mode=mode)

    def announce(self) -> None:
        """Broadcast MISSION_CURRENT when anything it carries changed (checked after every chunk:
        the message is built only then)."""
        key = self._current_fields()
        if key != self._announced:
            self._announced = key
            seq, total, state, mode = key
            self.srv.broadcast(M.MAVLink_mission_current_message(seq=seq, total=total, mission_state=state,
                                                                 mission_mode=mode))


def _mission_start(cmd, srv, channel):
    return srv.mission.start(cmd.p(1), cmd.p(2))


def _set_current(cmd, srv, channel):
    seq = cmd.p(1)
    return srv.mission.set_current(seq if seq is None or math.isfinite(seq) else None)


#: COMMAND_LONG/INT handlers of the mission (registered in commands.HANDLERS)
MISSION_COMMANDS = {
    M.MAV_CMD_MISSION_START: _mission_start,
    M.MAV_CMD_DO_SET_MISSION_CURRENT: _set_current,
}
