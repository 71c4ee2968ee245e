"""Position messages: one builder per message, ``(snapshot, ctx) -> message``.

The rig's virtual position is world ENU about the local origin; MAVLink's local frame is
NED about the same origin, and the origin sits at ``ctx.home`` on the globe
(:mod:`protocol.frames`, :mod:`protocol.geodesy`). The virtual GPS is ideal: 3D fix,
the true position, ten satellites, HDOP/VDOP 1.0.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from protocol.dialect import mavlink
from protocol.frames import (enu_to_ned_xyz, mavlink_euler_from_rwb_xyz, mavlink_quaternion_from_rwb_xyz,
                             paper_yaw_to_mavlink_xyz, rwb_from_quaternion_xyz)
from protocol.geodesy import TangentPlane
from rig_emulator.link.telemetry import units as U
from rig_emulator.link.telemetry.attitude import thrust_fraction

GPS_SATELLITES = 10
GPS_DOP = 1.0
GPS_ACCURACY_M = 0.01
IGNORE_ACCEL = (mavlink.POSITION_TARGET_TYPEMASK_AX_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_AY_IGNORE
                | mavlink.POSITION_TARGET_TYPEMASK_AZ_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE)
IGNORE_POS_VEL = (mavlink.POSITION_TARGET_TYPEMASK_X_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_Y_IGNORE
                  | mavlink.POSITION_TARGET_TYPEMASK_Z_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_VX_IGNORE
                  | mavlink.POSITION_TARGET_TYPEMASK_VY_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_VZ_IGNORE)


_plane = functools.lru_cache(maxsize=8)(TangentPlane)  # the home's frame, computed once per home


def enu_to_global(home, enu):
    """:func:`protocol.geodesy.local_enu_to_global` of one ENU offset, bit-identical where numpy's
    arctan2 is libm's (:class:`protocol.geodesy.TangentPlane`; within a few ulps elsewhere:
    tests/rig_emulator/link/telemetry/test_position_geodesy.py)."""
    e, n, u = enu
    return _plane(home).to_global(float(e), float(n), float(u))


def _global(snap, ctx, position=None):
    lat, lon, alt = enu_to_global(ctx.home, snap.position if position is None else position)
    return float(lat), float(lon), float(alt)


def _ned(v) -> tuple[float, float, float]:
    """protocol.frames.enu_to_ned of one vector, as floats."""
    return enu_to_ned_xyz(*v)


def _yaw(snap) -> float:
    return mavlink_euler_from_rwb_xyz(rwb_from_quaternion_xyz(*snap.quaternion))[2]


def local_position_ned(snap, ctx):
    x, y, z = _ned(snap.position)
    vx, vy, vz = _ned(snap.velocity)
    return mavlink.MAVLink_local_position_ned_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)


def position_target_local_ned(snap, ctx):
    """The guidance target; in attitude mode (no position target) positions are flagged ignored."""
    mask = IGNORE_ACCEL
    if not all(math.isfinite(v) for v in snap.position_target):
        mask |= IGNORE_POS_VEL
        pos = vel = (0.0, 0.0, 0.0)
    else:
        pos, vel = _ned(snap.position_target), _ned(snap.velocity_target)
    yaw = paper_yaw_to_mavlink_xyz(float(snap.euler_target[2]))
    return mavlink.MAVLink_position_target_local_ned_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), coordinate_frame=mavlink.MAV_FRAME_LOCAL_NED, type_mask=mask,
        x=float(pos[0]), y=float(pos[1]), z=float(pos[2]), vx=float(vel[0]), vy=float(vel[1]), vz=float(vel[2]),
        afx=0.0, afy=0.0, afz=0.0, yaw=yaw, yaw_rate=0.0)


def global_position_int(snap, ctx):
    lat, lon, alt = _global(snap, ctx)
    vn, ve, vd = _ned(snap.velocity)
    return mavlink.MAVLink_global_position_int_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), lat=U.deg_e7(lat), lon=U.deg_e7(lon), alt=U.mm(alt),
        relative_alt=U.mm(alt - ctx.home.alt_m), vx=U.cm_s_i16(vn), vy=U.cm_s_i16(ve), vz=U.cm_s_i16(vd),
        hdg=U.heading_rad_to_cdeg(_yaw(snap)))


def gps_raw_int(snap, ctx):
    lat, lon, alt = _global(snap, ctx)
    vn, ve, _ = _ned(snap.velocity)
    ground_speed = math.hypot(vn, ve)
    cog = U.heading_rad_to_cdeg(math.atan2(ve, vn)) if ground_speed > 0.01 else U.UINT16_UNKNOWN
    accuracy_mm = U.mm(GPS_ACCURACY_M)
    return mavlink.MAVLink_gps_raw_int_message(
        time_usec=U.time_usec(snap.stamp_us), fix_type=mavlink.GPS_FIX_TYPE_3D_FIX, lat=U.deg_e7(lat), lon=U.deg_e7(lon),
        alt=U.mm(alt), eph=int(GPS_DOP * 100), epv=int(GPS_DOP * 100), vel=U.cm_s_u16(ground_speed), cog=cog,
        satellites_visible=GPS_SATELLITES, alt_ellipsoid=U.mm(alt), h_acc=accuracy_mm, v_acc=accuracy_mm,
        vel_acc=accuracy_mm, hdg_acc=0, yaw=0)


def home_position(snap, ctx):
    """Home: the local origin (``--home``) moved by DO_SET_HOME (its height stays on the ground)."""
    enu = ctx.flight.tasks.home if ctx.flight is not None else np.zeros(3)
    lat, lon, alt = enu_to_global(ctx.home, enu)
    n, e, d = _ned(enu)
    return mavlink.MAVLink_home_position_message(
        latitude=U.deg_e7(lat), longitude=U.deg_e7(lon), altitude=U.mm(alt),
        x=n, y=e, z=d, q=[1.0, 0.0, 0.0, 0.0], approach_x=0.0, approach_y=0.0, approach_z=0.0,
        time_usec=U.time_usec(snap.stamp_us))


def vfr_hud(snap, ctx):
    _, _, alt = _global(snap, ctx)
    vn, ve, vd = _ned(snap.velocity)
    speed = math.hypot(vn, ve)
    return mavlink.MAVLink_vfr_hud_message(
        airspeed=speed, groundspeed=speed, heading=U.heading_rad_to_deg(_yaw(snap)),
        throttle=U.percent(thrust_fraction(snap.u[0], ctx.cfg)), alt=alt, climb=-float(vd))


def sim_state(snap, ctx):
    """The true state (the physics, not the rig's estimates): attitude, specific force at the
    joint, body rates, virtual position and velocity."""
    r_true = rwb_from_quaternion_xyz(*snap.true_quaternion)
    w, x, y, z = mavlink_quaternion_from_rwb_xyz(r_true)
    roll, pitch, yaw = mavlink_euler_from_rwb_xyz(r_true)
    lat, lon, alt = _global(snap, ctx, snap.true_position)
    vn, ve, vd = _ned(snap.true_velocity)
    g = float(ctx.cfg["airframe.gravity"])
    # true specific force, FRD: R^T [0, 0, g], summed as numpy's matrix-vector product (from +0, in order)
    acc = [((0.0 + r_true[i] * 0.0) + r_true[3 + i] * 0.0) + r_true[6 + i] * g for i in range(3)]
    return mavlink.MAVLink_sim_state_message(
        q1=float(w), q2=float(x), q3=float(y), q4=float(z), roll=roll, pitch=pitch, yaw=yaw,
        xacc=acc[0], yacc=acc[1], zacc=acc[2],
        xgyro=snap.true_body_rates[0], ygyro=snap.true_body_rates[1], zgyro=snap.true_body_rates[2],
        lat=lat, lon=lon, alt=alt, std_dev_horz=0.0, std_dev_vert=0.0,
        vn=vn, ve=ve, vd=vd, lat_int=U.deg_e7(lat), lon_int=U.deg_e7(lon))
