"""Flight modes in PX4's custom-mode layout, which MAVSDK and QGroundControl decode.

HEARTBEAT.custom_mode = ``main << 16 | sub << 24`` with PX4's main modes (MANUAL 1,
ALTCTL 2, POSCTL 3, AUTO 4, ACRO 5, OFFBOARD 6, STABILIZED 7) and AUTO sub-modes
(READY 1, TAKEOFF 2, LOITER 3, MISSION 4, RTL 5, LAND 6).

What each mode does to the rig is a handler ``enter(rig) -> None`` registered per
``(main, sub)``; a mode without a handler is refused (MAV_RESULT_UNSUPPORTED). The rig's
own handlers:

* POSCTL and AUTO.LOITER: hold the current position (:meth:`LiveRig.hold_position`);
* STABILIZED: hold a level attitude at the current heading (position loop off);
* OFFBOARD: keep the current target; SET_POSITION_TARGET_LOCAL_NED and
  SET_ATTITUDE_TARGET then steer the rig (they also switch to OFFBOARD themselves).

AUTO.MISSION is registered by the mission executor (:mod:`rig_emulator.link.mission.executor`).
A handler that returns ``False`` refuses the mode (the mode does not change).
"""

from __future__ import annotations

from typing import Callable

MANUAL, ALTCTL, POSCTL, AUTO, ACRO, OFFBOARD, STABILIZED = 1, 2, 3, 4, 5, 6, 7
AUTO_READY, AUTO_TAKEOFF, AUTO_LOITER, AUTO_MISSION, AUTO_RTL, AUTO_LAND = 1, 2, 3, 4, 5, 6

MODE_NAMES = {
    (MANUAL, 0): "MANUAL", (ALTCTL, 0): "ALTCTL", (POSCTL, 0): "POSCTL", (ACRO, 0): "ACRO",
    (OFFBOARD, 0): "OFFBOARD", (STABILIZED, 0): "STABILIZED",
    (AUTO, AUTO_READY): "AUTO.READY", (AUTO, AUTO_TAKEOFF): "AUTO.TAKEOFF", (AUTO, AUTO_LOITER): "AUTO.LOITER",
    (AUTO, AUTO_MISSION): "AUTO.MISSION", (AUTO, AUTO_RTL): "AUTO.RTL", (AUTO, AUTO_LAND): "AUTO.LAND",
}


def custom_mode(main: int, sub: int) -> int:
    """PX4's packing of a (main, sub) mode into HEARTBEAT.custom_mode."""
    return (main << 16) | (sub << 24)


def split_custom_mode(value: int) -> tuple[int, int]:
    return (value >> 16) & 0xFF, (value >> 24) & 0xFF


def _hold_position(rig) -> None:
    rig.hold_position()


def _stabilized(rig) -> None:
    psi = rig.snapshot().euler[2]
    rig.set_attitude_target(0.0, 0.0, psi)


def _keep_target(rig) -> None:
    """OFFBOARD: the set-point messages steer; entering changes nothing."""


class FlightModes:
    """The current mode and the handlers that put the rig into each mode."""

    def __init__(self):
        self.main, self.sub = POSCTL, 0
        self._enter: dict[tuple[int, int], Callable] = {}
        self.register(POSCTL, 0, _hold_position)
        self.register(AUTO, AUTO_LOITER, _hold_position)
        self.register(STABILIZED, 0, _stabilized)
        self.register(OFFBOARD, 0, _keep_target)

    def register(self, main: int, sub: int, enter: Callable) -> None:
        self._enter[(main, sub)] = enter

    def supports(self, main: int, sub: int) -> bool:
        return (main, sub) in self._enter

    @property
    def custom_mode(self) -> int:
        return custom_mode(self.main, self.sub)

    @property
    def name(self) -> str:
        return MODE_NAMES.get((self.main, self.sub), f"{self.main}.{self.sub}")

    def enter(self, main: int, sub: int, rig) -> bool:
        """Switch to (main, sub); False (and no change) when the mode is not supported or refused."""
        enter = self._enter.get((main, sub))
        if enter is None or enter(rig) is False:
            return False
        self.main, self.sub = main, sub
        return True

    def note(self, main: int, sub: int) -> None:
        """Record a mode the rig is already in (e.g. OFFBOARD set by a set-point message)."""
        self.main, self.sub = main, sub
