"""Offboard set-point frames (protocol/setpoint_frames.py): type_mask and MAV_FRAME readings."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from protocol.dialect import mavlink as M
from protocol.geodesy import Home, local_enu_to_global
from protocol.setpoint_frames import SetpointRefused, global_setpoint, local_setpoint

POS = M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE | M.POSITION_TARGET_TYPEMASK_Z_IGNORE
VEL = M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE
ACC = M.POSITION_TARGET_TYPEMASK_AX_IGNORE | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
YAW = M.POSITION_TARGET_TYPEMASK_YAW_IGNORE
RATE = M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
HOME = Home(35.7, 51.4, 1200.0)


def local(frame, mask, x=(0, 0, 0), v=(0, 0, 0), a=(0, 0, 0), yaw=0.0, yaw_rate=0.0):
    return M.MAVLink_set_position_target_local_ned_message(0, 1, 1, frame, mask, *x, *v, *a, yaw, yaw_rate)


def glob(frame, mask, lat=0, lon=0, alt=0.0, v=(0, 0, 0), yaw=0.0):
    return M.MAVLink_set_position_target_global_int_message(0, 1, 1, frame, mask, lat, lon, alt, *v, 0, 0, 0, yaw, 0.0)


def test_local_ned_position_and_yaw_in_world_terms():
    sp = local_setpoint(local(M.MAV_FRAME_LOCAL_NED, VEL | ACC | RATE, x=(1.0, 2.0, -3.0), yaw=0.0), (0, 0, 0), 0.0)
    assert np.allclose(sp.position, [2.0, 1.0, 3.0])  # NED (north 1, east 2, down -3) -> ENU
    assert np.all(np.isnan(sp.velocity)) and np.all(np.isnan(sp.acceleration))
    assert sp.yaw == pytest.approx(math.pi / 2) and sp.yaw_rate is None  # facing north = paper psi pi/2


def test_velocity_only_leaves_position_uncontrolled_and_yaw_rate_turns_the_other_way():
    sp = local_setpoint(local(M.MAV_FRAME_LOCAL_NED, POS | ACC | YAW, v=(0.5, 0.0, -0.2), yaw_rate=0.3), (0, 0, 0), 0.0)
    assert np.all(np.isnan(sp.position))
    assert np.allclose(sp.velocity, [0.0, 0.5, 0.2])
    assert sp.yaw is None and sp.yaw_rate == pytest.approx(-0.3)  # clockwise seen from above is -psi


def test_single_axis_ignore_bits_are_per_component():
    mask = M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE | ACC | YAW | RATE
    sp = local_setpoint(local(M.MAV_FRAME_LOCAL_NED, mask, x=(9, 9, -2.0), v=(1.0, 0.0, 9.0)), (0, 0, 0), 0.0)
    assert np.isnan(sp.position[0]) and np.isnan(sp.position[1]) and sp.position[2] == pytest.approx(2.0)
    assert sp.velocity[1] == pytest.approx(1.0) and sp.velocity[0] == pytest.approx(0.0) and np.isnan(sp.velocity[2])


def test_offset_and_body_frames_use_position_and_heading():
    here_ned, heading = (10.0, -5.0, -2.0), math.pi / 2  # facing east
    sp = local_setpoint(local(M.MAV_FRAME_LOCAL_OFFSET_NED, VEL | ACC | YAW | RATE, x=(1.0, 0.0, -1.0)), here_ned, heading)
    assert np.allclose(sp.position, [-5.0, 11.0, 3.0])
    sp = local_setpoint(local(M.MAV_FRAME_BODY_OFFSET_NED, VEL | ACC | YAW | RATE, x=(1.0, 0.0, 0.0)), here_ned, heading)
    assert np.allclose(sp.position, [-4.0, 10.0, 2.0])  # one metre forward = one metre east
    sp = local_setpoint(local(M.MAV_FRAME_BODY_NED, POS | ACC | YAW | RATE, v=(2.0, 0.0, 0.0)), here_ned, heading)
    assert np.allclose(sp.velocity, [2.0, 0.0, 0.0])  # forward while facing east: +X (east)
    sp = local_setpoint(local(M.MAV_FRAME_BODY_NED, VEL | ACC | YAW | RATE, x=(1.0, 2.0, -3.0)), here_ned, heading)
    assert np.allclose(sp.position, [2.0, 1.0, 3.0])  # BODY_NED positions are local NED (the spec)


@pytest.mark.parametrize("frame,mask,why", [
    (M.MAV_FRAME_GLOBAL_INT, VEL | ACC | YAW | RATE, "not a local set-point frame"),
    (M.MAV_FRAME_LOCAL_NED, VEL | ACC | YAW | RATE | M.POSITION_TARGET_TYPEMASK_FORCE_SET, "force"),
    (M.MAV_FRAME_LOCAL_NED, POS | VEL | ACC, "nothing to follow"),
    (M.MAV_FRAME_LOCAL_NED, VEL | ACC | YAW | RATE | 0x1000, "not POSITION_TARGET_TYPEMASK bits"),
])
def test_refused_with_a_reason(frame, mask, why):
    with pytest.raises(SetpointRefused, match=why):
        local_setpoint(local(frame, mask), (0, 0, 0), 0.0)


def test_non_finite_used_values_are_refused_but_ignored_ones_are_not():
    with pytest.raises(SetpointRefused, match="not a finite"):
        local_setpoint(local(M.MAV_FRAME_LOCAL_NED, VEL | ACC | YAW | RATE, x=(math.nan, 0, 0)), (0, 0, 0), 0.0)
    sp = local_setpoint(local(M.MAV_FRAME_LOCAL_NED, POS | ACC | YAW | RATE, x=(math.nan,) * 3, v=(1, 0, 0)), (0, 0, 0), 0.0)
    assert np.allclose(sp.velocity, [0.0, 1.0, 0.0])


def test_global_int_relative_and_amsl_agree():
    lat, lon, _ = local_enu_to_global(HOME, [3.0, 4.0, 2.0])
    for frame, alt in ((M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 2.0), (M.MAV_FRAME_GLOBAL_INT, HOME.alt_m + 2.0)):
        sp = global_setpoint(glob(frame, VEL | ACC | YAW | RATE, round(lat * 1e7), round(lon * 1e7), alt), HOME)
        assert np.allclose(sp.position, [3.0, 4.0, 2.0], atol=0.02)
    with pytest.raises(SetpointRefused, match="terrain"):
        global_setpoint(glob(M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT, VEL | ACC | YAW | RATE), HOME)
    with pytest.raises(SetpointRefused, match="together"):
        global_setpoint(glob(M.MAV_FRAME_GLOBAL_INT, M.POSITION_TARGET_TYPEMASK_X_IGNORE | VEL | ACC | YAW | RATE), HOME)


@given(st.floats(-3.0, 3.0), st.floats(-5, 5), st.floats(-5, 5))
def test_body_velocity_keeps_its_length_and_vertical(yaw, vx, vy):
    sp = local_setpoint(local(M.MAV_FRAME_BODY_NED, POS | ACC | YAW | RATE, v=(vx, vy, 1.0)), (0, 0, 0), yaw)
    assert np.hypot(sp.velocity[0], sp.velocity[1]) == pytest.approx(np.hypot(vx, vy), abs=1e-5)
    assert sp.velocity[2] == pytest.approx(-1.0)
