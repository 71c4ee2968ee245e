"""Set-point messages for scripted experiments (PX4's offboard interface).

* SET_POSITION_TARGET_LOCAL_NED (MAV_FRAME_LOCAL_NED, position bits used): the position
  is converted NED -> ENU and held with :meth:`LiveRig.set_position_target`; yaw (NED,
  rad) becomes the paper's psi unless YAW_IGNORE is set.
* SET_ATTITUDE_TARGET (attitude used): the quaternion of R_NED_FRD becomes
  R_WB = T_NED_ENU R_NED_FRD and the paper's Euler angles for
  :meth:`LiveRig.set_attitude_target` (the position loop is off).

Both switch the reported flight mode to OFFBOARD. Each function returns None when the
set-point was applied, else the reason it was dropped (the caller counts it).
"""

from __future__ import annotations

import math

import numpy as np

from protocol.dialect import mavlink as M
from protocol.frames import T_NED_ENU, mavlink_euler_to_paper, ned_to_enu, paper_euler_from_rwb
from rig_emulator.link.commands.modes import OFFBOARD
from rig_emulator.physics.rotation import quat_to_rot

POSITION_BITS = (M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE
                 | M.POSITION_TARGET_TYPEMASK_Z_IGNORE)


def rwb_from_mavlink_quaternion(q) -> np.ndarray:
    """R_WB of a MAVLink attitude quaternion (w, x, y, z) of R_NED_FRD (normalised first)."""
    w, x, y, z = (float(v) for v in q)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    r = np.zeros((3, 3))
    quat_to_rot(w / n, x / n, y / n, z / n, r)
    return T_NED_ENU @ r


def apply_position_target(msg, rig, modes) -> str | None:
    if msg.coordinate_frame != M.MAV_FRAME_LOCAL_NED:
        return "unsupported_frame"
    if msg.type_mask & POSITION_BITS:
        return "unsupported_setpoint"
    ned = (msg.x, msg.y, msg.z)
    if not all(math.isfinite(v) for v in ned):
        return "invalid"
    yaw = None
    if not msg.type_mask & M.POSITION_TARGET_TYPEMASK_YAW_IGNORE:
        if not math.isfinite(msg.yaw):
            return "invalid"
        yaw = mavlink_euler_to_paper(0.0, 0.0, msg.yaw)[2]
    rig.set_position_target(ned_to_enu(ned), yaw)
    modes.note(OFFBOARD, 0)
    return None


def apply_attitude_target(msg, rig, modes) -> str | None:
    if msg.type_mask & M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE:
        return "unsupported_setpoint"
    q = [float(v) for v in msg.q]
    norm = math.sqrt(sum(v * v for v in q)) if all(math.isfinite(v) for v in q) else math.nan
    if not 0.5 < norm < 1.5:
        return "invalid"
    phi, theta, psi = paper_euler_from_rwb(rwb_from_mavlink_quaternion(q))
    rig.set_attitude_target(phi, theta, psi)
    modes.note(OFFBOARD, 0)
    return None
