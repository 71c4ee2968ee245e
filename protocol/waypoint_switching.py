"""The waypoint logic of Sec. 4-4, shared by the rig (on-board missions) and the ground tools.

Between waypoints the rig follows a time-parameterised virtual line from where it was when
the leg began to the next waypoint; the line's duration is the time left to reach it,
``T = max(distance / speed, min_leg_time)``. Once the position error to the waypoint is
below the switching radius (8 cm in the paper) the rig proceeds to the next waypoint.

The functions are plain Python written in the subset numba compiles, and ``protocol`` (the
shared bottom layer) imports nothing from ``rig_emulator`` or ``gcs_tools``. The rig compiles
them once, with its cached compiler settings, in :mod:`rig_emulator.guidance.waypoint_switching`;
the step loop and the ground tools (``rig-gcs fly``) both call those compiled versions, so
both switch on bit-identical numbers.
"""

import math


def leg_duration(sx, sy, sz, tx, ty, tz, speed, min_leg_time):
    """Time budget of the virtual line from (sx, sy, sz) to (tx, ty, tz)."""
    d = math.sqrt((tx - sx) ** 2 + (ty - sy) ** 2 + (tz - sz) ** 2)
    return max(d / speed, min_leg_time)


def line_setpoint(t, t0, duration, sx, sy, sz, tx, ty, tz, out_pos, out_vel):
    """Desired position and velocity on the virtual line at time t (held at the end)."""
    tau = (t - t0) / duration
    if tau < 0.0:
        tau = 0.0
    moving = tau < 1.0
    if not moving:
        tau = 1.0
    out_pos[0] = sx + (tx - sx) * tau
    out_pos[1] = sy + (ty - sy) * tau
    out_pos[2] = sz + (tz - sz) * tau
    if moving:
        out_vel[0] = (tx - sx) / duration
        out_vel[1] = (ty - sy) / duration
        out_vel[2] = (tz - sz) / duration
    else:
        out_vel[0] = 0.0
        out_vel[1] = 0.0
        out_vel[2] = 0.0


def waypoint_reached(px, py, pz, tx, ty, tz, radius):
    """True when the position error to the waypoint is below the switching radius."""
    return (px - tx) ** 2 + (py - ty) ** 2 + (pz - tz) ** 2 < radius * radius
