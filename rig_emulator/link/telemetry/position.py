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
from protocol.frames import enu_to_ned, mavlink_euler_from_rwb, mavlink_quaternion_from_rwb, paper_euler_to_mavlink
from protocol.geodesy import ecef_to_enu_rotation, ecef_to_geodetic_xyz, geodetic_to_ecef
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


@functools.lru_cache(maxsize=8)
def _home_frame(home) -> tuple:
    """``ecef_to_enu_rotation`` and ``geodetic_to_ecef`` of ``home`` (read-only): what
    :func:`protocol.geodesy.local_enu_to_global` recomputes on every call."""
    r = ecef_to_enu_rotation(home.lat_deg, home.lon_deg)
    origin = geodetic_to_ecef(home.lat_deg, home.lon_deg, home.alt_m)
    r.setflags(write=False)
    origin.setflags(write=False)
    return r, origin


def enu_to_global(home, enu):
    """:func:`protocol.geodesy.local_enu_to_global` of one ENU offset, bit-identical: ``home``'s
    frame computed once, the conversion back to geodetic in scalar math
    (:func:`protocol.geodesy.ecef_to_geodetic_xyz`)."""
    r, origin = _home_frame(home)
    x, y, z = (origin + np.asarray(enu, dtype=float) @ r).tolist()
    return ecef_to_geodetic_xyz(x, y, z)


def _global(snap, ctx, position=None):
    lat, lon, alt = enu_to_global(ctx.home, snap.position if position is None else position)
    return float(lat), float(lon), float(alt)


def _yaw(snap) -> float:
    return mavlink_euler_from_rwb(snap.rotation)[2]


def local_position_ned(snap, ctx):
    x, y, z = enu_to_ned(snap.position)
    vx, vy, vz = enu_to_ned(snap.velocity)
    return mavlink.MAVLink_local_position_ned_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), x=float(x), y=float(y), z=float(z),
        vx=float(vx), vy=float(vy), vz=float(vz))


def position_target_local_ned(snap, ctx):
    """The guidance target; in attitude mode (no position target) positions are flagged ignored."""
    mask = IGNORE_ACCEL
    if not all(math.isfinite(v) for v in snap.position_target):
        mask |= IGNORE_POS_VEL
        pos = vel = (0.0, 0.0, 0.0)
    else:
        pos, vel = enu_to_ned(snap.position_target), enu_to_ned(snap.velocity_target)
    yaw = paper_euler_to_mavlink(*snap.euler_target)[2]
    return mavlink.MAVLink_position_target_local_ned_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), coordinate_frame=mavlink.MAV_FRAME_LOCAL_NED, type_mask=mask,
        x=float(pos[0]), y=float(pos[1]), z=float(pos[2]), vx=float(vel[0]), vy=float(vel[1]), vz=float(vel[2]),
        afx=0.0, afy=0.0, afz=0.0, yaw=yaw, yaw_rate=0.0)


def global_position_int(snap, ctx):
    lat, lon, alt = _global(snap, ctx)
    vn, ve, vd = enu_to_ned(snap.velocity)
    return mavlink.MAVLink_global_position_int_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), lat=U.deg_e7(lat), lon=U.deg_e7(lon), alt=U.mm(alt),
        relative_alt=U.mm(alt - ctx.home.alt_m), vx=U.cm_s_i16(vn), vy=U.cm_s_i16(ve), vz=U.cm_s_i16(vd),
        hdg=U.heading_rad_to_cdeg(_yaw(snap)))


def gps_raw_int(snap, ctx):
    lat, lon, alt = _global(snap, ctx)
    vn, ve, _ = enu_to_ned(snap.velocity)
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
    n, e, d = enu_to_ned(enu)
    return mavlink.MAVLink_home_position_message(
        latitude=U.deg_e7(lat), longitude=U.deg_e7(lon), altitude=U.mm(alt),
        x=float(n), y=float(e), z=float(d), q=[1.0, 0.0, 0.0, 0.0], approach_x=0.0, approach_y=0.0, approach_z=0.0,
        time_usec=U.time_usec(snap.stamp_us))


def vfr_hud(snap, ctx):
    _, _, alt = _global(snap, ctx)
    vn, ve, vd = enu_to_ned(snap.velocity)
    speed = math.hypot(vn, ve)
    return mavlink.MAVLink_vfr_hud_message(
        airspeed=speed, groundspeed=speed, heading=U.heading_rad_to_deg(_yaw(snap)),
        throttle=U.percent(thrust_fraction(snap.u[0], ctx.cfg)), alt=alt, climb=-float(vd))


def sim_state(snap, ctx):
    """The true state (the physics, not the rig's estimates): attitude, specific force at the
    joint, body rates, virtual position and velocity."""
    r_true = snap.true_rotation
    w, x, y, z = mavlink_quaternion_from_rwb(r_true)
    roll, pitch, yaw = mavlink_euler_from_rwb(r_true)
    lat, lon, alt = _global(snap, ctx, snap.true_position)
    vn, ve, vd = enu_to_ned(snap.true_velocity)
    acc = r_true.T @ np.array([0.0, 0.0, ctx.cfg["airframe.gravity"]])  # true specific force, FRD
    return mavlink.MAVLink_sim_state_message(
        q1=float(w), q2=float(x), q3=float(y), q4=float(z), roll=roll, pitch=pitch, yaw=yaw,
        xacc=float(acc[0]), yacc=float(acc[1]), zacc=float(acc[2]),
        xgyro=snap.true_body_rates[0], ygyro=snap.true_body_rates[1], zgyro=snap.true_body_rates[2],
        lat=lat, lon=lon, alt=alt, std_dev_horz=0.0, std_dev_vert=0.0,
        vn=float(vn), ve=float(ve), vd=float(vd), lat_int=U.deg_e7(lat), lon_int=U.deg_e7(lon))
