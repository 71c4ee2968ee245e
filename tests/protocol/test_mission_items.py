"""protocol.mission_items: wire round trips, validation results, frames about home, the plan."""

import math

import numpy as np
import pytest
from hypothesis import given, strategies as st

from protocol.dialect import mavlink as M
from protocol.geodesy import Home
from protocol.mission_items import (MissionItem, item_from_message, item_to_int_message, mission_plan,
                                    validate_item, waypoint_items)

HOME = Home(35.7, 51.4, 1200.0)
MAV = M.MAVLink(None, srcSystem=1, srcComponent=1)


def _wire(msg):
    """Pack and parse, as the link does."""
    out = M.MAVLink(None)
    return out.decode(bytearray(msg.pack(MAV)))


@given(st.integers(-900_000_000, 900_000_000), st.integers(-1_800_000_000, 1_800_000_000),
       st.sampled_from([M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_FRAME_GLOBAL_INT, M.MAV_FRAME_LOCAL_NED,
                        M.MAV_FRAME_LOCAL_ENU, M.MAV_FRAME_MISSION]))
def test_int_form_round_trips_exactly(x, y, frame):
    msg = M.MAVLink_mission_item_int_message(1, 1, 3, frame, 16, 0, 1, 0.5, 0.0, 0.0, 0.0, x, y, 2.5, 0)
    item = item_from_message(_wire(msg))
    back = _wire(item_to_int_message(item, 1, 1))
    assert (back.x, back.y, back.z, back.frame, back.seq) == (x, y, 2.5, frame, 3)


def test_scaling_by_frame():
    it = item_from_message(M.MAVLink_mission_item_int_message(1, 1, 0, M.MAV_FRAME_LOCAL_NED, 16, 0, 1, 0, 0, 0, 0,
                                                              12_345, -5_000, -2.0, 0))
    assert (it.x, it.y) == (1.2345, -0.5)
    it = item_from_message(M.MAVLink_mission_item_int_message(1, 1, 0, M.MAV_FRAME_GLOBAL_INT, 16, 0, 1, 0, 0, 0, 0,
                                                              357_000_000, 514_000_000, 1200.0, 0))
    assert (it.x, it.y) == (35.7, 51.4)


@pytest.mark.parametrize("item,result", [
    (MissionItem(0, M.MAV_FRAME_LOCAL_ENU, M.MAV_CMD_NAV_WAYPOINT, z=1.0), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_LOCAL_ENU, M.MAV_CMD_NAV_LOITER_TURNS), M.MAV_MISSION_UNSUPPORTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_RETURN_TO_LAUNCH), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_DELAY, param1=2.0), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_DELAY, param1=-1.0), M.MAV_MISSION_INVALID_PARAM1),
    (MissionItem(0, M.MAV_FRAME_LOCAL_ENU, M.MAV_CMD_NAV_LOITER_TIME, param1=3.0, z=1.0), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_JUMP, param1=0.0, param2=3.0), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_JUMP, param1=0.5, param2=3.0), M.MAV_MISSION_INVALID_PARAM1),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_JUMP, param1=0.0, param2=101.0), M.MAV_MISSION_INVALID_PARAM2),
    (MissionItem(0, M.MAV_FRAME_GLOBAL_TERRAIN_ALT, M.MAV_CMD_NAV_WAYPOINT), M.MAV_MISSION_UNSUPPORTED_FRAME),
    (MissionItem(0, M.MAV_FRAME_LOCAL_ENU, M.MAV_CMD_NAV_WAYPOINT, param1=math.inf), M.MAV_MISSION_INVALID_PARAM1),
    (MissionItem(0, M.MAV_FRAME_LOCAL_ENU, M.MAV_CMD_NAV_WAYPOINT, x=math.nan), M.MAV_MISSION_INVALID_PARAM5_X),
    (MissionItem(0, M.MAV_FRAME_LOCAL_ENU, M.MAV_CMD_NAV_LAND, x=math.nan, y=math.nan), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_GLOBAL, M.MAV_CMD_NAV_TAKEOFF, z=1199.0), M.MAV_MISSION_INVALID_PARAM7),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_CHANGE_SPEED, param2=-1.0), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_CHANGE_SPEED, param2=101.0), M.MAV_MISSION_INVALID_PARAM2),
    (MissionItem(0, M.MAV_FRAME_GLOBAL_INT, M.MAV_CMD_HILMS_SYSID, param1=1.0), M.MAV_MISSION_ACCEPTED),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_HILMS_SYSID, param1=0.0), M.MAV_MISSION_INVALID_PARAM1),
    (MissionItem(0, M.MAV_FRAME_MISSION, M.MAV_CMD_HILMS_SYSID, param1=math.nan), M.MAV_MISSION_INVALID_PARAM1),
])
def test_validation_results(item, result):
    assert validate_item(item, HOME)[0] == result


@pytest.mark.parametrize("frame", [M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_FRAME_GLOBAL_INT,
                                   M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_LOCAL_ENU])
def test_waypoints_come_back_in_every_frame(frame):
    rect = [[0.0, 0.0, 2.0], [5.0, 0.0, 2.0], [5.0, 3.0, 2.0], [0.0, 3.0, 2.0]]
    plan = mission_plan(waypoint_items(rect, HOME, frame=frame, speed_m_s=0.8), HOME)
    assert plan.seqs == (1, 2, 3, 4) and np.all(plan.speeds == np.float32(0.8))
    assert np.allclose(plan.waypoints, rect, atol=6e-3)  # 1e-7 deg is 1.1 cm of latitude: half of it at worst


def test_item0_home_and_nav_index():
    items = waypoint_items([[0, 0, 0], [1, 0, 1], [2, 0, 1]], HOME)
    px4 = mission_plan(items, HOME)
    ardu = mission_plan(items, HOME, item0_home=True)
    assert px4.seqs == (0, 1, 2) and ardu.seqs == (1, 2) and ardu.first_seq == 1
    assert ardu.nav_index(0) == 0 and ardu.nav_index(2) == 1 and ardu.nav_index(3) is None


def test_takeoff_and_land_in_place():
    items = [MissionItem(0, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_CMD_NAV_TAKEOFF, z=1.5),
             MissionItem(1, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_CMD_NAV_LAND, x=0.0, y=0.0, z=3.0)]
    plan = mission_plan(items, HOME)
    assert list(plan.free_xy) == [1.0, 1.0] and plan.waypoints[0, 2] == 1.5 and plan.waypoints[1, 2] == 0.0


def test_plan_unrolls_jumps_and_ends_at_a_return():
    """DO_JUMP repeats its legs param2 times; NAV_DELAY holds where the rig is; NAV_RETURN_TO_LAUNCH ends the legs."""
    enu = M.MAV_FRAME_LOCAL_ENU
    items = [MissionItem(0, enu, M.MAV_CMD_NAV_TAKEOFF, z=1.0),
             MissionItem(1, enu, M.MAV_CMD_NAV_WAYPOINT, x=1.0, z=1.0),
             MissionItem(2, enu, M.MAV_CMD_NAV_WAYPOINT, x=2.0, z=1.0),
             MissionItem(3, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_JUMP, param1=1.0, param2=2.0),
             MissionItem(4, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_DELAY, param1=1.5),
             MissionItem(5, enu, M.MAV_CMD_NAV_LOITER_TIME, param1=2.0, x=3.0, z=1.0),
             MissionItem(6, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_RETURN_TO_LAUNCH),
             MissionItem(7, enu, M.MAV_CMD_NAV_WAYPOINT, x=9.0, z=1.0)]
    plan = mission_plan(items, HOME)
    assert plan.seqs == (0, 1, 2, 1, 2, 1, 2, 4, 5)
    assert plan.return_seq == 6
    assert list(plan.holds[-2:]) == [1.5, 2.0] and list(plan.free_xy[-2:]) == [2.0, 0.0]
    assert plan.nav_index(4) == 7
    with pytest.raises(ValueError, match="jump target 8"):
        mission_plan(items[:3] + [MissionItem(3, M.MAV_FRAME_MISSION, M.MAV_CMD_DO_JUMP, param1=8.0, param2=1.0)],
                     HOME)


def test_the_identification_flight_item_ends_the_mission():
    """MAV_CMD_HILMS_SYSID ends the legs (its programme ends disarmed): nothing may follow it."""
    enu = M.MAV_FRAME_LOCAL_ENU
    sysid = MissionItem(2, M.MAV_FRAME_MISSION, M.MAV_CMD_HILMS_SYSID, param1=1.0)
    items = [MissionItem(0, enu, M.MAV_CMD_NAV_TAKEOFF, z=1.0), MissionItem(1, M.MAV_FRAME_MISSION, M.MAV_CMD_NAV_DELAY,
                                                                           param1=2.0), sysid]
    plan = mission_plan(items, HOME)
    assert plan.seqs == (0, 1) and plan.sysid_seq == 2 and plan.return_seq == -1
    only = mission_plan([sysid.with_seq(0)], HOME)
    assert only.size == 0 and only.sysid_seq == 0
    with pytest.raises(ValueError, match="item 3: nothing may follow item 2 MAV_CMD_HILMS_SYSID"):
        mission_plan(items + [MissionItem(3, enu, M.MAV_CMD_NAV_WAYPOINT, x=1.0, z=1.0)], HOME)
