"""Offboard set-point frames: SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT fields -> the rig's
world ENU (m, m/s, m/s^2) and paper heading, in one named place.

Frames (MAVLink ``MAV_FRAME`` definitions, read as PX4 and ArduPilot apply them: a body
frame is rotated by the vehicle's heading only, never by roll and pitch):

* ``MAV_FRAME_LOCAL_NED``: position, velocity, acceleration in local NED about home.
* ``MAV_FRAME_LOCAL_OFFSET_NED``: the position is an offset (NED) from the current position;
  velocity and acceleration are NED.
* ``MAV_FRAME_BODY_NED``: the position is local NED ("same as LOCAL_NED for positions");
  velocity and acceleration are in the heading frame (x forward, y right, z down).
* ``MAV_FRAME_BODY_OFFSET_NED``: the position is an offset in the heading frame from the
  current position; velocity and acceleration in the heading frame.
* Global frames (SET_POSITION_TARGET_GLOBAL_INT): latitude/longitude (degE7) with the
  altitude AMSL (``GLOBAL_INT``) or above home (``GLOBAL_RELATIVE_ALT_INT``); velocity and
  acceleration NED. ``GLOBAL_TERRAIN_ALT_INT`` needs terrain data the rig has none of.

Headings: MAVLink yaw (NED, clockwise from north) -> paper psi (ENU, counter-clockwise from
east) is ``psi = pi/2 - yaw`` (:func:`protocol.frames.mavlink_euler_to_paper`), so a yaw
rate becomes ``-yaw_rate``.

``type_mask`` (POSITION_TARGET_TYPEMASK): each ignore bit makes that one component NaN
("not controlled", as PX4 builds its trajectory set-point); FORCE_SET (afx..afz are forces)
is refused, as PX4 refuses it. Bits 12-15 (PX4's old takeoff/land/loiter/idle hints) are not
part of the message's definition and are refused too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from protocol.dialect import mavlink as M
from protocol.frames import ned_to_enu
from protocol.geodesy import Home, global_to_local_enu

X_BITS = (M.POSITION_TARGET_TYPEMASK_X_IGNORE, M.POSITION_TARGET_TYPEMASK_Y_IGNORE, M.POSITION_TARGET_TYPEMASK_Z_IGNORE)
V_BITS = (M.POSITION_TARGET_TYPEMASK_VX_IGNORE, M.POSITION_TARGET_TYPEMASK_VY_IGNORE,
          M.POSITION_TARGET_TYPEMASK_VZ_IGNORE)
A_BITS = (M.POSITION_TARGET_TYPEMASK_AX_IGNORE, M.POSITION_TARGET_TYPEMASK_AY_IGNORE,
          M.POSITION_TARGET_TYPEMASK_AZ_IGNORE)
KNOWN_BITS = sum(X_BITS + V_BITS + A_BITS) | M.POSITION_TARGET_TYPEMASK_FORCE_SET | \
    M.POSITION_TARGET_TYPEMASK_YAW_IGNORE | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
LOCAL_SETPOINT_FRAMES = (M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_LOCAL_OFFSET_NED, M.MAV_FRAME_BODY_NED,
                         M.MAV_FRAME_BODY_OFFSET_NED)
GLOBAL_SETPOINT_FRAMES = (M.MAV_FRAME_GLOBAL_INT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                          M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_RELATIVE_ALT)


class SetpointRefused(ValueError):
    """A set-point the rig cannot follow; the message says why (sent as STATUSTEXT)."""


@dataclass(frozen=True)
class WorldSetpoint:
    """A set-point in the rig's terms: world ENU (NaN = not controlled), paper psi (None = not given)."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    yaw: float | None
    yaw_rate: float | None


def frame_name(frame: int) -> str:
    entry = M.enums["MAV_FRAME"].get(frame)
    return entry.name if entry is not None else str(frame)


def _masked(values, mask: int, bits) -> np.ndarray:
    return np.array([math.nan if mask & b else float(v) for v, b in zip(values, bits)])


def _heading_rotation(yaw_ned: float) -> np.ndarray:
    """R of the heading frame (x forward, y right, z down) in NED: a rotation about down by yaw."""
    c, s = math.cos(yaw_ned), math.sin(yaw_ned)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _common(msg) -> tuple[np.ndarray, np.ndarray, float | None, float | None]:
    mask = int(msg.type_mask)
    if mask & ~KNOWN_BITS & 0xFFFF:
        raise SetpointRefused(f"type_mask 0x{mask:04x}: bits 0x{mask & ~KNOWN_BITS:04x} are not POSITION_TARGET_TYPEMASK bits")
    if mask & M.POSITION_TARGET_TYPEMASK_FORCE_SET:
        raise SetpointRefused("force set-points (FORCE_SET) are not supported; send accelerations")
    vel = _masked((msg.vx, msg.vy, msg.vz), mask, V_BITS)
    acc = _masked((msg.afx, msg.afy, msg.afz), mask, A_BITS)
    yaw = None if mask & M.POSITION_TARGET_TYPEMASK_YAW_IGNORE else float(msg.yaw)
    yaw_rate = None if mask & M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE else float(msg.yaw_rate)
    for name, v in (("yaw", yaw), ("yaw_rate", yaw_rate)):
        if v is not None and not math.isfinite(v):
            raise SetpointRefused(f"{name} {v} is not a finite number")
    return vel, acc, yaw, yaw_rate


def _finish(pos_ned, vel_ned, acc_ned, yaw, yaw_rate, mask) -> WorldSetpoint:
    for name, v, bits in (("position", pos_ned, X_BITS), ("velocity", vel_ned, V_BITS),
                          ("acceleration", acc_ned, A_BITS)):
        given = np.array([not mask & b for b in bits])
        if not np.all(np.isfinite(v[given])):
            raise SetpointRefused(f"{name} is not a finite number where type_mask uses it")
    if np.all(np.isnan(pos_ned)) and np.all(np.isnan(vel_ned)) and np.all(np.isnan(acc_ned)):
        raise SetpointRefused("type_mask ignores position, velocity and acceleration: nothing to follow")
    psi = None if yaw is None else math.pi / 2.0 - yaw
    if psi is not None:
        psi = (psi + math.pi) % (2.0 * math.pi) - math.pi
    return WorldSetpoint(position=ned_to_enu(pos_ned), velocity=ned_to_enu(vel_ned), acceleration=ned_to_enu(acc_ned),
                         yaw=psi, yaw_rate=None if yaw_rate is None else -yaw_rate)


def local_setpoint(msg, position_ned, yaw_ned: float) -> WorldSetpoint:
    """A SET_POSITION_TARGET_LOCAL_NED in world terms; ``position_ned`` and ``yaw_ned`` are
    where the rig is and its heading now (for the offset and body frames)."""
    frame = msg.coordinate_frame
    if frame not in LOCAL_SETPOINT_FRAMES:
        raise SetpointRefused(f"frame {frame_name(frame)} is not a local set-point frame "
                              "(LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED)")
    mask = int(msg.type_mask)
    vel, acc, yaw, yaw_rate = _common(msg)
    pos = _masked((msg.x, msg.y, msg.z), mask, X_BITS)
    rot = _heading_rotation(yaw_ned)
    if frame in (M.MAV_FRAME_BODY_NED, M.MAV_FRAME_BODY_OFFSET_NED):
        vel = rot @ np.nan_to_num(vel, nan=0.0) + np.where(np.isnan(vel), math.nan, 0.0)
        acc = rot @ np.nan_to_num(acc, nan=0.0) + np.where(np.isnan(acc), math.nan, 0.0)
    if frame == M.MAV_FRAME_BODY_OFFSET_NED:
        if np.isnan(pos[0]) != np.isnan(pos[1]):
            raise SetpointRefused("BODY_OFFSET_NED: x and y offsets must be given (or ignored) together")
        pos = rot @ np.nan_to_num(pos, nan=0.0) + np.where(np.isnan(pos), math.nan, 0.0)
    if frame in (M.MAV_FRAME_LOCAL_OFFSET_NED, M.MAV_FRAME_BODY_OFFSET_NED):
        pos = pos + np.asarray(position_ned, dtype=float)
    return _finish(pos, vel, acc, yaw, yaw_rate, mask)


def global_setpoint(msg, home: Home) -> WorldSetpoint:
    """A SET_POSITION_TARGET_GLOBAL_INT in world terms (about ``home``)."""
    frame = msg.coordinate_frame
    if frame == M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT or frame == M.MAV_FRAME_GLOBAL_TERRAIN_ALT:
        raise SetpointRefused("terrain-relative altitude: the rig has no terrain data")
    if frame not in GLOBAL_SETPOINT_FRAMES:
        raise SetpointRefused(f"frame {frame_name(frame)} is not a global set-point frame "
                              "(GLOBAL_INT, GLOBAL_RELATIVE_ALT_INT)")
    mask = int(msg.type_mask)
    vel, acc, yaw, yaw_rate = _common(msg)
    pos_ned = np.full(3, math.nan)
    xy_given = not (mask & X_BITS[0] or mask & X_BITS[1])
    if bool(mask & X_BITS[0]) != bool(mask & X_BITS[1]):
        raise SetpointRefused("latitude and longitude must be given (or ignored) together")
    alt_given = not mask & X_BITS[2]
    if xy_given or alt_given:
        lat, lon = msg.lat_int / 1e7, msg.lon_int / 1e7
        if xy_given and not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise SetpointRefused(f"latitude {lat:g} / longitude {lon:g} out of range")
        alt = float(msg.alt)
        if alt_given and not math.isfinite(alt):
            raise SetpointRefused(f"altitude {alt} is not a finite number")
        amsl = alt + home.alt_m if frame in (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT) else alt
        enu = np.asarray(global_to_local_enu(home, lat if xy_given else home.lat_deg, lon if xy_given else home.lon_deg,
                                             amsl if alt_given else home.alt_m), dtype=float)
        ned = np.array([enu[1], enu[0], -enu[2]])
        pos_ned = np.array([ned[0] if xy_given else math.nan, ned[1] if xy_given else math.nan,
                            ned[2] if alt_given else math.nan])
    return _finish(pos_ned, vel, acc, yaw, yaw_rate, mask)
