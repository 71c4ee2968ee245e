"""Flight tasks a flight controller runs on top of its guidance: take-off, landing (with a
land detector that disarms), return to home, fly-to and hold.

No MAVLink here: the link (:mod:`rig_emulator.link.commands.flight_commands`) starts tasks and reads
what :meth:`FlightTasks.poll` reports. Every task is a short path of Sec. 4-4 virtual
lines flown by the rig's own waypoint guidance (:meth:`LiveRig.fly_path`), so take-off,
landing and return follow the same reference shaping as a mission. World ENU, metres,
about the local origin; the virtual ground is Z = 0 (``sim.ground``).

Settings (config keys, MAVLink names as PX4's): ``guidance.takeoff_altitude``
(MIS_TAKEOFF_ALT, above home), ``guidance.return_altitude`` (RTL_RETURN_ALT, above home),
``guidance.land_speed`` (MPC_LAND_SPEED).

Land detector (Reading: a simplified PX4 land detector; the rig has no contact sensor):
once a landing descent has started, the rig is *landed* when the height it flies on
(its estimate with the sensor models on) stays below :data:`LANDED_HEIGHT_M` with a speed
below :data:`LANDED_SPEED_M_S` for :data:`LANDED_TIME_S` of simulated time; it then
disarms.
"""

from __future__ import annotations

import math

import numpy as np

LANDED_HEIGHT_M = 0.10
LANDED_SPEED_M_S = 0.15
LANDED_TIME_S = 1.0
CLIMB_MARGIN_M = 0.05  # a return does not climb when it is already within this of its altitude

TAKEOFF, LAND, RETURN, GOTO = "takeoff", "land", "return", "goto"


class FlightTasks:
    """The task the rig's guidance is flying, if any (one at a time)."""

    def __init__(self, rig):
        self.rig = rig
        self.home = np.zeros(3)  # home, world ENU; Z stays on the virtual ground
        self.task: str | None = None
        self.pending: str | None = None  # a take-off commanded while disarmed: starts on arming
        self._pending_altitude = 0.0
        self.landing = False  # the land detector is on
        self._low_since: float | None = None

    # --- settings -------------------------------------------------------------------------
    @property
    def takeoff_altitude(self) -> float:
        return float(self.rig.cfg["guidance.takeoff_altitude"])

    @property
    def return_altitude(self) -> float:
        return float(self.rig.cfg["guidance.return_altitude"])

    @property
    def land_speed(self) -> float:
        return float(self.rig.cfg["guidance.land_speed"])

    # --- starting tasks -----------------------------------------------------------------------
    def _start(self, task: str, waypoints, speeds=None, free_xy=None, landing: bool = False) -> None:
        n = len(waypoints)
        self.rig.fly_path(waypoints, speeds=np.zeros(n) if speeds is None else speeds,
                          free_xy=np.zeros(n) if free_xy is None else free_xy)
        self.task, self.pending = task, None
        self.landing = landing
        self._low_since = None

    def takeoff(self, altitude: float | None = None, armed: bool = True) -> float:
        """Climb at the current X/Y to ``altitude`` above home (default the take-off altitude
        setting); disarmed, the climb starts when the rig is armed. Returns the altitude."""
        alt = self.takeoff_altitude if altitude is None else float(altitude)
        if not (0.0 < alt < 1e4 and math.isfinite(alt)):
            raise ValueError(f"take-off altitude {alt:g} m must be above the ground")
        if not armed:
            self.cancel()
            self.pending, self._pending_altitude = TAKEOFF, alt
            return alt
        self._start(TAKEOFF, [[0.0, 0.0, alt]], free_xy=[1.0])
        return alt

    def land(self) -> None:
        """Descend at the current X/Y to the ground at the land speed, then disarm."""
        self._start(LAND, [[0.0, 0.0, 0.0]], speeds=[self.land_speed], free_xy=[1.0], landing=True)

    def return_home(self) -> float:
        """Climb to the return altitude if lower, fly to home at that height, land there.
        Returns the altitude of the return leg."""
        z = float(self.rig.position_now()[2])
        alt = max(z, self.return_altitude)
        hx, hy = float(self.home[0]), float(self.home[1])
        legs, speeds, free = [], [], []
        if z < alt - CLIMB_MARGIN_M:
            legs.append([0.0, 0.0, alt]), speeds.append(0.0), free.append(1.0)
        legs += [[hx, hy, alt], [hx, hy, 0.0]]
        speeds += [0.0, self.land_speed]
        free += [0.0, 0.0]
        self._start(RETURN, legs, speeds=speeds, free_xy=free, landing=True)
        return alt

    def goto(self, position, speed: float | None = None) -> None:
        """Fly to ``position`` (world ENU) on a virtual line and hold there."""
        p = np.asarray(position, dtype=float).reshape(3)
        if p[2] < 0.0:
            raise ValueError(f"target {p[2]:.2f} m below the ground")
        self._start(GOTO, [p], speeds=[0.0 if speed is None else float(speed)])

    def hold(self) -> None:
        """Stop whatever is flown and hold the current position."""
        self.cancel()
        self.rig.hold_position()

    def cancel(self) -> None:
        """Forget the task (another mode steers now); the guidance is left as it is."""
        self.task, self.pending, self.landing, self._low_since = None, None, False, None

    def watch_landing(self) -> None:
        """Turn the land detector on for a descent flown by someone else (a mission's land)."""
        if not self.landing:
            self.landing, self._low_since = True, None

    def set_home(self, position) -> None:
        """Home at ``position``'s X/Y (world ENU); its height stays on the virtual ground."""
        p = np.asarray(position, dtype=float).reshape(3)
        if not np.all(np.isfinite(p[:2])):
            raise ValueError("home position must be finite")
        self.home = np.array([p[0], p[1], 0.0])

    # --- progress ---------------------------------------------------------------------------------
    def poll(self, snap) -> list[str]:
        """After a physics chunk: what happened ("takeoff started", "takeoff complete",
        "arrived", "landed")."""
        events: list[str] = []
        if self.pending == TAKEOFF and snap.armed:
            self._start(TAKEOFF, [[0.0, 0.0, self._pending_altitude]], free_xy=[1.0])
            events.append("takeoff started")
        if self.task in (TAKEOFF, GOTO):
            st = self.rig.path_status()
            if not st.flying:
                self.task = None
            elif st.done:
                events.append("takeoff complete" if self.task == TAKEOFF else "arrived")
                self.task = None
        if self.landing:
            if not snap.armed:
                self.landing, self.task, self._low_since = False, None, None
            elif self._landed_now(snap):
                self.rig.arm(False)
                self.landing, self.task, self._low_since = False, None, None
                events.append("landed")
        return events

    def _landed_now(self, snap) -> bool:
        z = snap.position[2]
        speed = math.sqrt(sum(v * v for v in snap.velocity))
        if z < LANDED_HEIGHT_M and speed < LANDED_SPEED_M_S:
            if self._low_since is None:
                self._low_since = snap.time_s
            return snap.time_s - self._low_since >= LANDED_TIME_S
        self._low_since = None
        return False
