"""Flight modes: PX4's, in PX4's custom-mode layout, with the rig's HEARTBEAT saying
MAV_AUTOPILOT_PX4 so that every client decodes them as PX4's (pymavlink/MAVProxy's
``px4_map``, MAVSDK's ``px4_custom_mode``, QGroundControl's PX4FirmwarePlugin).

HEARTBEAT.custom_mode = ``main << 16 | sub << 24`` with PX4's main modes (MANUAL 1,
ALTCTL 2, POSCTL 3, AUTO 4, ACRO 5, OFFBOARD 6, STABILIZED 7, RATTITUDE 8) and sub-modes
(POSCTL: ORBIT 1; AUTO: READY 1, TAKEOFF 2, LOITER 3, MISSION 4, RTL 5, LAND 6, RTGS 7,
FOLLOW_TARGET 8, PRECLAND 9, and the rig's identification flight in PX4's first external-mode slot,
EXTERNAL1 11: :mod:`rig_emulator.link.commands.sysid_flight`).

Every PX4 mode is in :data:`MODES`. The ones the rig flies have a handler ``enter(rig)``
registered (:mod:`rig_emulator.link.commands.flight_control`, :mod:`rig_emulator.link.mission.executor`,
:mod:`rig_emulator.link.commands.offboard_setpoints`: OFFBOARD only with a fresh set-point
stream); the others carry the reason the rig refuses them
(:meth:`FlightModes.refusal`), which the link sends as a STATUSTEXT after a DENIED ACK. A
handler that returns ``False`` or a reason (str) refuses the mode (the mode does not
change; the reason is kept in :attr:`FlightModes.last_refusal`).

Standard modes (MAV_STANDARD_MODE, :mod:`rig_emulator.link.commands.standard_modes`): POSCTL is
POSITION_HOLD, AUTO.MISSION MISSION, AUTO.RTL SAFE_RECOVERY, AUTO.LAND LAND, AUTO.TAKEOFF
TAKEOFF (PX4's own mapping); the others are non-standard.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from protocol.px4_custom_mode import RIG_MODES, custom_mode, split_custom_mode  # noqa: F401 - the rig's names for them

MANUAL, ALTCTL, POSCTL, AUTO, ACRO, OFFBOARD, STABILIZED, RATTITUDE = 1, 2, 3, 4, 5, 6, 7, 8
AUTO_READY, AUTO_TAKEOFF, AUTO_LOITER, AUTO_MISSION, AUTO_RTL, AUTO_LAND = 1, 2, 3, 4, 5, 6
AUTO_RTGS, AUTO_FOLLOW_TARGET, AUTO_PRECLAND = 7, 8, 9
#: the identification flight's mode: PX4's first external-mode slot (PX4_CUSTOM_SUB_MODE_EXTERNAL1), where
#: PX4 reports a mode an onboard component adds (ROS 2 external modes), named in AVAILABLE_MODES
AUTO_SYSID = RIG_MODES["SYSID"][1]
POSCTL_ORBIT = 1

# MAV_STANDARD_MODE values (common.xml)
STD_NON_STANDARD, STD_POSITION_HOLD, STD_SAFE_RECOVERY, STD_MISSION, STD_LAND, STD_TAKEOFF = 0, 1, 5, 6, 7, 8

_NO_STICKS = "needs stick input (RC or MANUAL_CONTROL), which the rig does not take; use POSCTL or AUTO.LOITER"


@dataclass(frozen=True)
class Mode:
    name: str  # PX4's name, as pymavlink and PX4's logs print it
    label: str  # QGroundControl's / PX4's user-facing name (AVAILABLE_MODES.mode_name)
    standard: int = STD_NON_STANDARD
    refusal: str = ""  # why the rig refuses it ("" = flown when a handler is registered)


MODES: dict[tuple[int, int], Mode] = {
    (MANUAL, 0): Mode("MANUAL", "Manual", refusal="MANUAL " + _NO_STICKS),
    (ALTCTL, 0): Mode("ALTCTL", "Altitude", refusal="ALTCTL " + _NO_STICKS),
    (POSCTL, 0): Mode("POSCTL", "Position", STD_POSITION_HOLD),
    (POSCTL, POSCTL_ORBIT): Mode("POSCTL.ORBIT", "Orbit", refusal="ORBIT: MAV_CMD_DO_ORBIT is not implemented"),
    (ACRO, 0): Mode("ACRO", "Acro", refusal="ACRO " + _NO_STICKS),
    (RATTITUDE, 0): Mode("RATTITUDE", "Rattitude", refusal="RATTITUDE " + _NO_STICKS),
    (STABILIZED, 0): Mode("STABILIZED", "Stabilized"),
    (OFFBOARD, 0): Mode("OFFBOARD", "Offboard"),
    (AUTO, AUTO_READY): Mode("AUTO.READY", "Ready", refusal="AUTO.READY is a state, not a mode one switches to"),
    (AUTO, AUTO_TAKEOFF): Mode("AUTO.TAKEOFF", "Takeoff", STD_TAKEOFF),
    (AUTO, AUTO_LOITER): Mode("AUTO.LOITER", "Hold"),
    (AUTO, AUTO_MISSION): Mode("AUTO.MISSION", "Mission", STD_MISSION),
    (AUTO, AUTO_RTL): Mode("AUTO.RTL", "Return", STD_SAFE_RECOVERY),
    (AUTO, AUTO_LAND): Mode("AUTO.LAND", "Land", STD_LAND),
    (AUTO, AUTO_RTGS): Mode("AUTO.RTGS", "Return to Groundstation",
                            refusal="AUTO.RTGS needs the ground station's position, which the rig is never told"),
    (AUTO, AUTO_FOLLOW_TARGET): Mode("AUTO.FOLLOW_TARGET", "Follow Me",
                                     refusal="FOLLOW_TARGET messages are not handled by the rig"),
    (AUTO, AUTO_PRECLAND): Mode("AUTO.PRECLAND", "Precision Land",
                                refusal="AUTO.PRECLAND needs a landing-target sensor, which the rig has not"),
    (AUTO, AUTO_SYSID): Mode("AUTO.SYSID", "System ID"),
}
MODE_NAMES = {key: m.name for key, m in MODES.items()}


class FlightModes:
    """The current mode and the handlers that put the rig into each mode."""

    def __init__(self):
        self.main, self.sub = POSCTL, 0
        self._enter: dict[tuple[int, int], Callable] = {}
        self.on_leave: Callable | None = None  # (old, new) after every change of mode
        self.last_refusal = ""  # why the last enter() was refused by its handler

    def register(self, main: int, sub: int, enter: Callable) -> None:
        self._enter[(main, sub)] = enter

    def supports(self, main: int, sub: int) -> bool:
        return (main, sub) in self._enter

    def refusal(self, main: int, sub: int) -> str:
        """Why (main, sub) cannot be entered: the mode's reason, or that it is not a PX4 mode."""
        mode = MODES.get((main, sub))
        if mode is None:
            return f"mode {main}.{sub} is not a PX4 mode (custom_mode {custom_mode(main, sub)})"
        return mode.refusal or f"{mode.name} is not available"

    @property
    def custom_mode(self) -> int:
        return custom_mode(self.main, self.sub)

    @property
    def name(self) -> str:
        return self.name_of(self.main, self.sub)

    @property
    def standard_mode(self) -> int:
        mode = MODES.get((self.main, self.sub))
        return STD_NON_STANDARD if mode is None else mode.standard

    def available(self) -> list[tuple[tuple[int, int], Mode]]:
        """The modes the rig flies, in MODES order (AVAILABLE_MODES)."""
        return [(key, m) for key, m in MODES.items() if key in self._enter]

    def enter(self, main: int, sub: int, rig) -> bool:
        """Switch to (main, sub); False (and no change) when the mode is not supported or refused."""
        enter = self._enter.get((main, sub))
        if enter is None:
            self.last_refusal = self.refusal(main, sub)
            return False
        outcome = enter(rig)
        if outcome is False or isinstance(outcome, str):
            self.last_refusal = outcome if isinstance(outcome, str) else f"{self.name_of(main, sub)} refused"
            return False
        self.note(main, sub)
        return True

    @staticmethod
    def name_of(main: int, sub: int) -> str:
        return MODE_NAMES.get((main, sub), f"{main}.{sub}")

    def note(self, main: int, sub: int) -> None:
        """Record a mode the rig is already in (e.g. AUTO.LOITER once a take-off completes)."""
        old = (self.main, self.sub)
        self.main, self.sub = main, sub
        if self.on_leave is not None:
            self.on_leave(old, (main, sub))
