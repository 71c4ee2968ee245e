"""Guidance: turns the configured task into the controller's references each control update.

Types (``GuidanceParams.gtype``): HOVER (a fixed set-point), ATTITUDE (harmonic attitude of
Eq. 44 about ``att_offset``; zero amplitude and offset for stabilisation), HELIX (Eq. 46), WAYPOINTS (Sec. 4-4 with the
shared switching logic in ``protocol.waypoint_switching``), OFFBOARD (an external set-point,
:mod:`rig_emulator.guidance.offboard`).

Waypoint memory ``gstate`` (GS_* indices) and ``reached_t`` (time each waypoint was
reached, NaN until then) live in arrays so a running rig can swap missions between chunks.

Per waypoint ``i`` the guidance arguments carry: ``radii[i]`` (switching radius),
``holds[i]`` (hold time once reached), ``speeds[i]`` (speed of the leg that ends at ``i``;
0 = the rig's ``speed``) and ``free_xy[i]`` (1 = the target's X and Y are where the rig is
when the leg starts: a take-off, or a landing "here"; 2 = X, Y and Z: a delay or a loiter
"here"). The target of the current leg is
resolved once, when the leg starts, into ``gstate[GS_TARGET:GS_TARGET + 3]``.
"""

import math

from rig_emulator._jit import jit
from rig_emulator.control.controller import (
    MODE_ATTITUDE,
    MODE_POSITION,
    REF_ACC,
    REF_ATT,
    REF_ATT_ACC,
    REF_ACC_FF,
    REF_ATT_RATE,
    REF_MODE,
    REF_POS,
    REF_THRUST,
    REF_VEL,
    REF_YAW,
)
from rig_emulator.guidance.offboard import offboard_references
from rig_emulator.guidance.trajectories import harmonic_attitude, helix_eq46
from rig_emulator.guidance.waypoint_switching import leg_duration, line_setpoint, waypoint_reached

HOVER = 0
ATTITUDE = 1
HELIX = 2
WAYPOINTS = 3
OFFBOARD = 4  # an external set-point (guidance/offboard.py); only a running rig selects it
# "sysid": the identification flight (guidance/sysid.py) flies offboard attitude set-points it writes
# between the loop's chunks; it starts as a level attitude hold
GUIDANCE_CODES = {"hover": HOVER, "attitude": ATTITUDE, "helix": HELIX, "waypoints": WAYPOINTS, "sysid": ATTITUDE}

GS_INDEX = 0  # waypoint being flown to
GS_T0 = 1  # start time of the current virtual line
GS_DURATION = 2  # its time budget
GS_START = 3  # 3: where the line starts
GS_HOLD_UNTIL = 6  # end of a hold at a reached waypoint, -1 when not holding
GS_DONE = 7  # 1 once the last waypoint is reached
GS_STARTED = 8  # 0 until the first leg is set up
GS_TARGET = 9  # 9: the current leg's target (the waypoint, X/Y resolved for free_xy legs)
GS_SIZE = 12


@jit(nrt=False)
def _start_leg(t, pos, gp, gstate):
    i = int(gstate[GS_INDEX])
    gstate[GS_T0] = t
    gstate[GS_START] = pos[0]
    gstate[GS_START + 1] = pos[1]
    gstate[GS_START + 2] = pos[2]
    wp = gp.waypoints
    if gp.free_xy[i] != 0.0:
        gstate[GS_TARGET] = pos[0]
        gstate[GS_TARGET + 1] = pos[1]
    else:
        gstate[GS_TARGET] = wp[i, 0]
        gstate[GS_TARGET + 1] = wp[i, 1]
    gstate[GS_TARGET + 2] = wp[i, 2] if gp.free_xy[i] != 2.0 else pos[2]  # 2: hold here (NAV_DELAY)
    speed = gp.speeds[i] if gp.speeds[i] > 0.0 else gp.speed
    gstate[GS_DURATION] = leg_duration(pos[0], pos[1], pos[2], gstate[GS_TARGET], gstate[GS_TARGET + 1],
                                       gstate[GS_TARGET + 2], speed, gp.min_leg_time)


@jit(nrt=False)
def _advance(t, pos, gp, gstate):
    gstate[GS_HOLD_UNTIL] = -1.0
    gstate[GS_INDEX] += 1.0
    if int(gstate[GS_INDEX]) >= gp.waypoints.shape[0]:
        gstate[GS_INDEX] = gp.waypoints.shape[0] - 1
        gstate[GS_DONE] = 1.0
    else:
        _start_leg(t, pos, gp, gstate)


@jit(nrt=False, python=True)  # also called from Python (live rig: missions)
def start_at(index, t, pos, gp, gstate):
    """Begin flying to waypoint ``index`` on a virtual line from ``pos`` at time t."""
    gstate[GS_STARTED] = 1.0
    gstate[GS_INDEX] = float(index)
    gstate[GS_HOLD_UNTIL] = -1.0
    gstate[GS_DONE] = 0.0
    _start_leg(t, pos, gp, gstate)


@jit(nrt=False)
def _waypoints(t, pos, gp, gstate, reached_t, ref):
    if gstate[GS_STARTED] == 0.0:
        start_at(0, t, pos, gp, gstate)
    i = int(gstate[GS_INDEX])
    tx = gstate[GS_TARGET]
    ty = gstate[GS_TARGET + 1]
    tz = gstate[GS_TARGET + 2]
    if gstate[GS_DONE] == 0.0:
        if gstate[GS_HOLD_UNTIL] >= 0.0:
            if t >= gstate[GS_HOLD_UNTIL]:
                _advance(t, pos, gp, gstate)
        elif waypoint_reached(pos[0], pos[1], pos[2], tx, ty, tz, gp.radii[i]):
            reached_t[i] = t
            if gp.holds[i] > 0.0:
                gstate[GS_HOLD_UNTIL] = t + gp.holds[i]
            else:
                _advance(t, pos, gp, gstate)
    if gstate[GS_DONE] != 0.0 or gstate[GS_HOLD_UNTIL] >= 0.0:
        for k in range(3):
            ref[REF_POS + k] = gstate[GS_TARGET + k]
            ref[REF_VEL + k] = 0.0
    else:
        line_setpoint(
            t, gstate[GS_T0], gstate[GS_DURATION],
            gstate[GS_START], gstate[GS_START + 1], gstate[GS_START + 2],
            gstate[GS_TARGET], gstate[GS_TARGET + 1], gstate[GS_TARGET + 2],
            ref[REF_POS : REF_POS + 3], ref[REF_VEL : REF_VEL + 3],
        )
    for k in range(3):
        ref[REF_ACC + k] = 0.0


@jit(nrt=False)
def guidance_update(t, pos, gp, gstate, reached_t, ref):
    """Fill ``ref`` (controller.REF_* layout) for time t and the current position."""
    if gp.gtype == OFFBOARD:
        offboard_references(t, gp.offboard, ref)
        return
    ref[REF_YAW] = gp.yaw
    ref[REF_THRUST] = math.nan  # the offboard references are unused outside OFFBOARD
    ref[REF_ACC_FF] = 0.0
    if gp.gtype == ATTITUDE:
        ref[REF_MODE] = MODE_ATTITUDE
        harmonic_attitude(
            t, gp.amplitude, gp.omega,
            ref[REF_ATT : REF_ATT + 3], ref[REF_ATT_RATE : REF_ATT_RATE + 3], ref[REF_ATT_ACC : REF_ATT_ACC + 3],
        )
        for k in range(3):
            ref[REF_ATT + k] += gp.att_offset[k]
        ref[REF_ATT + 2] += gp.yaw
        for k in range(3):
            ref[REF_POS + k] = math.nan
            ref[REF_VEL + k] = math.nan
            ref[REF_ACC + k] = 0.0
        return
    ref[REF_MODE] = MODE_POSITION
    if gp.gtype == HOVER:
        for k in range(3):
            ref[REF_POS + k] = gp.hover_position[k]
            ref[REF_VEL + k] = 0.0
            ref[REF_ACC + k] = 0.0
    elif gp.gtype == HELIX:
        helix_eq46(t, ref[REF_POS : REF_POS + 3], ref[REF_VEL : REF_VEL + 3], ref[REF_ACC : REF_ACC + 3])
    else:
        _waypoints(t, pos, gp, gstate, reached_t, ref)
