"""Mission plausibility and geofence checks at upload (protocol/mission_checks.py)."""

import math

from protocol.dialect import mavlink as M
from protocol.geodesy import Home
from protocol.mission_checks import MissionLimits, check_plan, fence_breach
from protocol.mission_items import MissionItem, mission_plan, waypoint_items

HOME = Home(35.7, 51.4, 1200.0)
FENCE = MissionLimits(fence_enabled=True, fence_radius_m=100.0, fence_alt_max_m=50.0, fence_alt_min_m=-10.0,
                      max_leg_m=900.0)


def _plan(points, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT):
    return mission_plan(waypoint_items(points, HOME, frame=frame), HOME)


def test_the_rectangle_is_plausible():
    rect = [[0, 0, 2], [5, 0, 2], [5, 3, 2], [0, 3, 2], [0, 0, 2]]
    assert check_plan(_plan(rect), FENCE) == (M.MAV_MISSION_ACCEPTED, "")


def test_outside_the_fence_names_the_field():
    result, why = check_plan(_plan([[0, 0, 2], [0, 150, 2]]), FENCE)
    assert result == M.MAV_MISSION_INVALID_PARAM5_X and "item 1" in why and "FENCE_RADIUS" in why  # north: x / lat
    result, _ = check_plan(_plan([[150, 0, 2]]), FENCE)
    assert result == M.MAV_MISSION_INVALID_PARAM6_Y  # east: y / lon
    result, why = check_plan(_plan([[0, 0, 60]]), FENCE)
    assert result == M.MAV_MISSION_INVALID_PARAM7 and "FENCE_ALT_MAX" in why


def test_fence_off_still_refuses_a_50_km_leg_and_a_waypoint_under_ground():
    limits = MissionLimits(max_leg_m=900.0)
    result, why = check_plan(_plan([[0, 0, 2], [0, 50_000, 2]]), limits)
    assert result == M.MAV_MISSION_INVALID_PARAM5_X and "50.00 km leg from item 0" in why
    result, why = check_plan(_plan([[1, 1, -2]]), limits)
    assert result == M.MAV_MISSION_INVALID_PARAM7 and "under the ground" in why
    assert check_plan(_plan([[1, 1, -2]]), MissionLimits(ground=False))[0] == M.MAV_MISSION_ACCEPTED


def test_mavproxy_scaled_local_items_land_kilometres_away_and_are_refused():
    # MAVProxy's wp load of a local-frame file: x/y * 1e7 on the wire, read as * 1e4 -> 1000x
    item = MissionItem(seq=0, frame=M.MAV_FRAME_LOCAL_NED, command=M.MAV_CMD_NAV_WAYPOINT, x=5000.0, y=0.0, z=-2.0)
    result, why = check_plan(mission_plan([item], HOME), FENCE)
    assert result == M.MAV_MISSION_INVALID_PARAM5_X and "5000.0 m from home" in why


def test_takeoff_and_land_here_are_measured_from_the_previous_waypoint():
    items = [MissionItem(seq=0, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, command=M.MAV_CMD_NAV_TAKEOFF, z=2.0),
             MissionItem(seq=1, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, command=M.MAV_CMD_NAV_LAND, x=math.nan)]
    assert check_plan(mission_plan(items, HOME), FENCE)[0] == M.MAV_MISSION_ACCEPTED


def test_fence_breach_reasons():
    assert fence_breach((0, 0, 0), FENCE) is None
    assert "fence radius" in fence_breach((80, 80, 1), FENCE)
    assert "above" in fence_breach((0, 0, 51), FENCE)
    assert "below" in fence_breach((0, 0, -11), FENCE)
    assert fence_breach((1e6, 0, 0), MissionLimits()) is None
