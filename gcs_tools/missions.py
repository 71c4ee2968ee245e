"""The paper's missions as MAVLink mission items, and mission items as rig waypoints.

Generators (world ENU in the paper's terms: X east, Y north, Z up; written as
MAV_CMD_NAV_WAYPOINT items with the switching radius as the acceptance radius, param2):

* :func:`rectangle` - Sec. 4-4 / Fig. 19: the corners of a W x H rectangle at one altitude,
  starting and ending at the origin corner: (0,0,Z) (W,0,Z) (W,H,Z) (0,H,Z) (0,0,Z).
* :func:`helix` - Eq. 46 (the 3D line, then the rising helix) sampled every ``spacing``
  metres of path from t = 3 s (where the line leaves the origin) to ``t_end``, the end
  point included. The published curve jumps at t = 12 s from (2.7, 2.7) to (2.5, 2.5)
  (see rig_emulator/guidance/trajectories.py); the waypoints keep the jump.

Frames: ``local`` writes MAV_FRAME_LOCAL_NED (x north, y east, z down, metres about the
rig's local origin; MISSION_ITEM_INT carries 0.1 mm); ``global`` writes
MAV_FRAME_GLOBAL_RELATIVE_ALT about a home position (latitude/longitude at 1e-7 degree,
about 1 cm; altitude above home) for ground stations that draw missions on a map.
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.errors import UsageError
from protocol.dialect import mavlink as M
from protocol.frames import enu_to_ned, ned_to_enu
from protocol.geodesy import Home, global_to_local_enu, local_enu_to_global
from protocol.mission_files import Mission, MissionItem

DEFAULT_RADIUS_M = 0.08  # Sec. 4-4
FLYABLE = {M.MAV_CMD_NAV_WAYPOINT: "NAV_WAYPOINT", M.MAV_CMD_NAV_TAKEOFF: "NAV_TAKEOFF"}
RELATIVE_FRAMES = (M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
AMSL_FRAMES = (M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_INT)


def rectangle_points(width: float, height: float, altitude: float) -> np.ndarray:
    if not (width > 0 and height > 0 and math.isfinite(width) and math.isfinite(height)):
        raise UsageError(f"rectangle {width:g}x{height:g}: both sides must be positive")
    if not math.isfinite(altitude):
        raise UsageError("altitude must be finite")
    z = altitude
    return np.array([[0.0, 0.0, z], [width, 0.0, z], [width, height, z], [0.0, height, z], [0.0, 0.0, z]])


def helix_points(spacing: float, t_end: float = 60.0, t_start: float = 3.0) -> np.ndarray:
    """Eq. 46 sampled every ``spacing`` m of path between ``t_start`` and ``t_end`` (s)."""
    from rig_emulator.guidance.trajectories import helix_eq46

    if not (spacing > 0 and math.isfinite(spacing)):
        raise UsageError(f"--spacing {spacing}: must be a positive number of metres")
    if not (t_end > t_start and math.isfinite(t_end)):
        raise UsageError(f"--t-end {t_end}: must be after {t_start:g} s")
    ts = np.arange(t_start, t_end, 0.005)
    ts = np.append(ts, t_end)
    pts = np.zeros((ts.size, 3))
    vel, acc = np.zeros(3), np.zeros(3)
    for i, t in enumerate(ts):
        helix_eq46(float(t), pts[i], vel, acc)
    out = [pts[0]]
    travelled = 0.0
    for i in range(1, ts.size):
        travelled += float(np.linalg.norm(pts[i] - pts[i - 1]))
        if travelled >= spacing:
            out.append(pts[i])
            travelled = 0.0
    if np.linalg.norm(out[-1] - pts[-1]) > 1e-9:
        out.append(pts[-1])
    return np.array(out)


def mission_from_enu(points, radius: float = DEFAULT_RADIUS_M, frame: str = "local",
                     home: Home | None = None) -> Mission:
    """NAV_WAYPOINT items through world-ENU ``points`` (m), acceptance radius ``radius`` (m)."""
    if not (radius > 0 and math.isfinite(radius)):
        raise UsageError(f"--radius {radius}: must be a positive number of metres")
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    items = []
    home_tuple = None if home is None else (home.lat_deg, home.lon_deg, home.alt_m)
    for k, p in enumerate(pts):
        if frame == "local":
            n, e, d = enu_to_ned(p)
            fr, x, y, z = M.MAV_FRAME_LOCAL_NED, float(n), float(e), float(d)
        elif frame == "global":
            if home is None:
                raise UsageError("global frame waypoints need a home position (--home LAT,LON,ALT)")
            lat, lon, _ = local_enu_to_global(home, p)
            fr, x, y, z = M.MAV_FRAME_GLOBAL_RELATIVE_ALT, float(lat), float(lon), float(p[2])
        else:
            raise UsageError(f"frame {frame!r}: use 'local' or 'global'")
        items.append(MissionItem(M.MAV_CMD_NAV_WAYPOINT, fr, (0.0, float(radius), 0.0, math.nan), x, y, z,
                                 True, k == 0))
    return Mission(tuple(items), home_tuple)


def waypoints_enu(mission: Mission, home: Home | None, default_radius: float = DEFAULT_RADIUS_M):
    """(points (N, 3) world ENU m, radii (N,)) of a mission's items, every item flown (item 0 too).

    Local items are metres about the vehicle's local origin; global items need ``home`` (the
    vehicle's HOME_POSITION, the origin of LOCAL_POSITION_NED). Raises UsageError naming the
    item for anything else.
    """
    pts, radii = [], []
    for k, it in enumerate(mission.items):
        if it.command not in FLYABLE:
            name = M.enums["MAV_CMD"][it.command].name if it.command in M.enums["MAV_CMD"] else it.command
            raise UsageError(f"mission item {k}: {name} cannot be flown as a position target "
                             f"(supported: {', '.join(FLYABLE.values())})")
        if it.frame == M.MAV_FRAME_LOCAL_NED:
            p = ned_to_enu([it.x, it.y, it.z])
        elif it.frame == M.MAV_FRAME_LOCAL_ENU:
            p = np.array([it.x, it.y, it.z])
        elif it.frame in RELATIVE_FRAMES or it.frame in AMSL_FRAMES:
            if home is None:
                raise UsageError(f"mission item {k}: a global position needs the vehicle's home position")
            alt = home.alt_m + it.z if it.frame in RELATIVE_FRAMES else it.z
            p = global_to_local_enu(home, it.x, it.y, alt)
        else:
            name = M.enums["MAV_FRAME"][it.frame].name if it.frame in M.enums["MAV_FRAME"] else it.frame
            raise UsageError(f"mission item {k}: frame {name} is not supported (use LOCAL_NED, LOCAL_ENU or a global frame)")
        r = it.params[1] if it.command == M.MAV_CMD_NAV_WAYPOINT else math.nan
        pts.append(np.asarray(p, dtype=float))
        radii.append(r if math.isfinite(r) and r > 0 else default_radius)
    if not pts:
        raise UsageError("the mission has no items")
    return np.array(pts), np.array(radii)
