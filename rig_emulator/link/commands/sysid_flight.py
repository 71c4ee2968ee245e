"""The identification flight served: MAV_CMD_HILMS_SYSID, its mode, and the mission item's programme.

The programme is the headless scenario ``sysid``'s (:mod:`rig_emulator.guidance.sysid`, one
definition), run on the rig's own simulated clock from the moment it starts
(:meth:`~rig_emulator.simulation.live.LiveRig.start_sysid`): 120 s of attitude chirps, thrust steps, a hover and
swings, for which it disarms and re-arms the rig itself; it ends disarmed, hanging on the joint.

* ``MAV_CMD_HILMS_SYSID`` param1 = 1 enters the mode AUTO.SYSID, which starts the programme;
  param1 = 0 aborts a programme being flown (nothing to abort: ACCEPTED). Another param1 is DENIED
  with a STATUSTEXT naming it; a start while one is flown is DENIED with where it is.
* AUTO.SYSID (HEARTBEAT main mode AUTO, sub mode 11, PX4's first external-mode slot; AVAILABLE_MODES
  names it "System ID"): entering it by any mode command starts the programme, armed only (refused
  with the reason otherwise). PX4 reports a mode an onboard component adds to it (a ROS 2 external
  mode) in this slot, and the programme is exactly that: an onboard mode that flies attitude
  set-points. It is not OFFBOARD: the set-points are the rig's own, so streamed offboard set-points
  are only stored (they are flown in OFFBOARD alone) and the offboard-loss failsafe, which watches
  OFFBOARD, does not apply; nor does the ground-station-loss failsafe (the programme needs no one,
  like a mission).
* As a mission item (:mod:`rig_emulator.link.mission.executor`): flown when the mission reaches it,
  in AUTO.MISSION; it is the mission's last item, and the mission is complete when it has been flown.

What stops it: a change of mode (the new mode steers), a disarm command, an arm command during a
disarmed swing, param1 = 0, and anything that disarms, arms or steers the rig behind its back (the
failsafe, a terminate action: the programme then stops itself, :class:`~rig_emulator.simulation.live.LiveRig`).
Stopped or done, the rig holds its position in AUTO.LOITER (disarmed where the programme or the stop
left it disarmed); a mission it was flying for is paused, or complete once the programme has ended.
While it runs, commands that need the rig still on the bench (reboot, motor test, calibration) are
refused with the reason, though the rig is disarmed during the swings.

Every part is announced as it starts ("sysid: roll chirp (3-17 s)") and the end or a stop with
where it was, by STATUSTEXT to every peer and the console.
"""

from __future__ import annotations

from protocol.dialect import mavlink as M
from rig_emulator.guidance.sysid import DURATION_S, PARTS
from rig_emulator.link.commands import modes as MD
from rig_emulator.link.commands.flight_commands import refuse, set_mode

ACCEPTED, DENIED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED
SYSID_MODE = (MD.AUTO, MD.AUTO_SYSID)
_SPANS = {name: (a, b) for name, a, b in PARTS}


class SysidFlight:
    """The identification flight of one server (``srv``: rig, modes, mission, statustext)."""

    def __init__(self, srv):
        self.srv = srv
        self.owner: str | None = None  # "mode" (AUTO.SYSID) or "mission" while a programme flies
        self._part: str | None = None  # the part last announced
        srv.modes.register(MD.AUTO, MD.AUTO_SYSID, self._enter_mode)

    @property
    def running(self) -> bool:
        return self.owner is not None

    def where(self) -> str:
        """'12.3 s, roll chirp' of the programme being flown."""
        st = self.srv.rig.sysid_status()
        return "not running" if st is None else f"{st.elapsed_s:.1f} s, {st.part}"

    def busy_refusal(self, what: str) -> str | None:
        """Why ``what`` (a command that needs the rig still) is refused now, or None."""
        if not self.running:
            return None
        return f"{what} refused: the identification flight is running ({self.where()}); abort it first"

    # --- starting ---------------------------------------------------------------------------------
    def _enter_mode(self, rig):
        """FlightModes handler of AUTO.SYSID: start the programme (a programme already flown for a
        mission goes on, now the mode's own)."""
        if self.running:
            self.owner = "mode"
            return True
        why = self._start("mode")
        return True if why is None else why

    def start_for_mission(self, seq: int) -> str | None:
        """The mission reached its MAV_CMD_HILMS_SYSID item ``seq``: fly the programme in AUTO.MISSION (a
        programme already flown in AUTO.SYSID goes on, now the mission's); the reason when it cannot start."""
        if self.running:
            self.owner = "mission"
            return None
        return self._start("mission", f"mission item {seq}")

    def _start(self, owner: str, by: str = "") -> str | None:
        try:
            self.srv.rig.start_sysid()
        except ValueError as exc:
            return f"sysid refused: {exc}"
        self.owner = owner
        self._part = None
        self.srv.event(f"sysid: identification flight started{' by ' + by if by else ''} ({DURATION_S:g} s)")
        return None

    # --- stopping ---------------------------------------------------------------------------------
    def left_mode(self, old: tuple, new: tuple) -> None:
        """After every change of mode: a programme stops when the mode it flies in (AUTO.SYSID, or
        AUTO.MISSION for a mission's) is left; the new mode's handler, which ran first, steers now.
        (Entering AUTO.SYSID or AUTO.MISSION during a programme hands it over: the handler took it.)"""
        if not self.running or new == old:
            return
        home = SYSID_MODE if self.owner == "mode" else (MD.AUTO, MD.AUTO_MISSION)
        if new != home:
            self.stop(f"mode {MD.FlightModes.name_of(*new)}", hold=False)

    def stop(self, reason: str, hold: bool = True) -> None:
        """Stop the programme being flown; with ``hold`` the rig holds its position in AUTO.LOITER when
        it was flying in AUTO.SYSID or for the mission (a mode change or the mission passes ``hold=False``:
        they steer next)."""
        if not self.running:
            return
        where = self.where()
        owner = self.owner
        self.owner = None
        self.srv.rig.stop_sysid()
        self.srv.statustext(None, M.MAV_SEVERITY_WARNING, f"sysid: stopped at {where}: {reason}")
        if owner == "mission":
            self.srv.mission.sysid_ended(done=False)
        if hold:
            self._hold()

    def _hold(self) -> None:
        srv = self.srv
        srv.rig.hold_position()
        if (srv.modes.main, srv.modes.sub) in (SYSID_MODE, (MD.AUTO, MD.AUTO_MISSION)):
            srv.modes.note(MD.AUTO, MD.AUTO_LOITER)
            srv.heartbeat_pending = True  # a command's answer sends it; poll() at once

    # --- progress -----------------------------------------------------------------------------------
    def poll(self) -> None:
        """After each physics chunk: announce a new part, end a programme that has been flown, or
        report one that stopped itself."""
        if not self.running:
            return
        srv = self.srv
        st = srv.rig.sysid_status()
        if st is None:  # the simulation restarted under it
            self.owner = None
            return
        if st.stopped is not None or st.done:
            if st.stopped is not None:  # (another guidance that took over steers on: no hold)
                self.stop(st.stopped, hold=not st.replaced)
            else:
                owner = self.owner
                self.owner = None
                srv.rig.stop_sysid()
                srv.event(f"sysid: done ({DURATION_S:g} s), disarmed")
                if owner == "mission":
                    srv.mission.sysid_ended(done=True)
                self._hold()
            if srv.heartbeat_pending:
                srv.heartbeat_pending = False
                srv.broadcast_heartbeat()
            return
        if st.part != self._part:
            self._part = st.part
            a, b = _SPANS[st.part]
            self.srv.event(f"sysid: {st.part} ({a:g}-{b:g} s)")


def sysid_command(cmd, srv, channel):
    """MAV_CMD_HILMS_SYSID (param1 1 start, 0 abort): (MAV_RESULT, messages after the ACK)."""
    flag = cmd.p(1)
    sysid = srv.sysid_flight
    if flag not in (0.0, 1.0):
        given = "unset" if flag is None else f"{flag:g}"
        return refuse(srv, f"sysid rejected: param1 ({given}) must be 1 (start the identification flight) or 0 "
                           "(abort)")
    if flag == 0.0:
        sysid.stop("aborted by command")
        return ACCEPTED, []
    if sysid.running:
        return refuse(srv, f"sysid refused: already flying ({sysid.where()}); param1 = 0 aborts it")
    return set_mode(srv, *SYSID_MODE)
