"""Plausibility and geofence checks of a whole mission at upload, shared by the rig and tools.

An uploaded mission is refused (MISSION_ACK with the MAV_MISSION_RESULT naming the field)
when an item it would fly to:

* lies outside the geofence (when the fence is enabled): further than ``fence_radius_m``
  from home horizontally (INVALID_PARAM5_X or INVALID_PARAM6_Y, whichever of north / east
  is larger; for a local item that is x / y, for a global one latitude / longitude; a global
  item's distance is measured along the ellipsoid, :func:`protocol.geodesy.surface_offset`),
  or above ``fence_alt_max_m`` / below ``fence_alt_min_m`` (INVALID_PARAM7);
* is under the virtual ground (``ground``; INVALID_PARAM7);
* ends a leg longer than ``max_leg_m`` (PX4's MIS_DIST_WPS, the first leg measured from home
  as PX4's MIS_DIST_1WP): INVALID_PARAM5_X / PARAM6_Y as above.

Altitudes are the item's frame's own (:func:`protocol.mission_items.item_height`: above
home, above mean sea level less home's altitude, or the local z), never the tangent plane's
up, which reads the Earth's curvature as depth far from home.

The positions are those the rig flies (:func:`protocol.mission_items.mission_plan`), so a
local-frame item scaled wrongly by a ground station (MAVProxy's ``wp load`` of a local file
multiplies x/y by 1e7, the spec says 1e4) is caught as a waypoint kilometres away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionPlan

GROUND_TOLERANCE_M = 1e-3  # float32 altitudes of an item on the ground


@dataclass(frozen=True)
class MissionLimits:
    fence_enabled: bool = False
    fence_radius_m: float = math.inf
    fence_alt_max_m: float = math.inf
    fence_alt_min_m: float = -math.inf
    ground: bool = True
    max_leg_m: float = math.inf


def _xy_field(delta_enu) -> int:
    """The item field that carries the larger horizontal component: x (north) or y (east)."""
    return M.MAV_MISSION_INVALID_PARAM5_X if abs(delta_enu[1]) >= abs(delta_enu[0]) else M.MAV_MISSION_INVALID_PARAM6_Y


def horizontal_distance(p) -> float:
    return float(math.hypot(p[0], p[1]))


def fence_breach(p, limits: MissionLimits) -> str | None:
    """Why world-ENU position ``p`` (about home) is outside the fence, or None (also when disabled)."""
    if not limits.fence_enabled:
        return None
    d = horizontal_distance(p)
    if d > limits.fence_radius_m:
        return f"{d:.1f} m from home, beyond the fence radius {limits.fence_radius_m:g} m"
    if p[2] > limits.fence_alt_max_m:
        return f"altitude {p[2]:.1f} m above the fence maximum {limits.fence_alt_max_m:g} m"
    if p[2] < limits.fence_alt_min_m:
        return f"altitude {p[2]:.1f} m below the fence minimum {limits.fence_alt_min_m:g} m"
    return None


def check_plan(plan: MissionPlan, limits: MissionLimits) -> tuple[int, str]:
    """(MAV_MISSION_RESULT, reason) for the flown positions of ``plan``; ACCEPTED and "" when plausible.

    Legs that start where the rig is (take-off, land here) are measured from the previous
    waypoint (home for the first)."""
    prev = np.zeros(3)
    prev_d = 0.0
    surface = plan.horizontal_m if plan.horizontal_m.shape[0] == plan.size else np.full(plan.size, np.nan)
    for i in range(plan.size):
        seq = plan.seqs[i]
        p = np.array(plan.waypoints[i], dtype=float)
        if plan.free_xy[i]:
            p[0], p[1] = prev[0], prev[1]
            d = prev_d
        else:
            d = float(surface[i]) if math.isfinite(surface[i]) else horizontal_distance(p)
        if limits.ground and p[2] < -GROUND_TOLERANCE_M:
            return M.MAV_MISSION_INVALID_PARAM7, f"item {seq}: altitude {p[2]:.2f} m is under the ground"
        if limits.fence_enabled:
            if d > limits.fence_radius_m:
                return _xy_field(p), (f"item {seq}: {d:.1f} m from home, outside the fence radius "
                                      f"{limits.fence_radius_m:g} m (FENCE_RADIUS)")
            if p[2] > limits.fence_alt_max_m:
                return M.MAV_MISSION_INVALID_PARAM7, (f"item {seq}: altitude {p[2]:.1f} m above the fence maximum "
                                                      f"{limits.fence_alt_max_m:g} m (FENCE_ALT_MAX)")
            if p[2] < limits.fence_alt_min_m:
                return M.MAV_MISSION_INVALID_PARAM7, (f"item {seq}: altitude {p[2]:.1f} m below the fence minimum "
                                                      f"{limits.fence_alt_min_m:g} m (FENCE_ALT_MIN)")
        leg = float(np.linalg.norm(p - prev))
        if leg > limits.max_leg_m:
            start = "home" if i == 0 else f"item {plan.seqs[i - 1]}"
            return _xy_field(p - prev), (f"item {seq}: a {leg / 1000.0:.2f} km leg from {start}, longer than "
                                         f"{limits.max_leg_m:g} m (MIS_DIST_WPS)")
        prev, prev_d = p, d
    return M.MAV_MISSION_ACCEPTED, ""
