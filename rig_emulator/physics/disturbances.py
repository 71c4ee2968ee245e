"""External disturbances: wind and gusts (forces in Eq. 1), shocks and extra masses (torques in Eq. 3).

Arrays (all SI, mutable while the rig runs):

* ``wind``: constant wind force, world ENU, N (3,).
* ``gusts``: rows ``(t_start, duration, fx, fy, fz)``: 1-cosine gusts added to the wind.
* ``shocks``: rows ``(t_start, arm, torque, duration)``: Fig. 12's impulsive disturbances,
  a rectangular push on arm ``arm`` (1..4) whose torque about the joint is ``torque``
  (positive pushes the arm tip down, i.e. along +z_B).
* ``extra``: rows per arm ``(mass, distance)``: Fig. 15's point masses. Reading: they
  change the inertia and add a gravity torque about the joint; the virtual translation
  (Eq. 1) keeps the airframe mass m, as the rig's onboard computer does.

Arm directions in B follow A6: arm 1 +x, arm 2 +y, arm 3 -x, arm 4 -y.
"""

import math

from rig_emulator._jit import jit

@jit
def arm_direction(arm_index):
    """Unit vector (x, y) in B of arm ``arm_index`` (0-based, A6 numbering minus one)."""
    if arm_index == 0:
        return 1.0, 0.0
    if arm_index == 1:
        return 0.0, 1.0
    if arm_index == 2:
        return -1.0, 0.0
    return 0.0, -1.0


@jit(nrt=False)
def wind_force(t, wind, gusts):
    """Wind plus active 1-cosine gusts at time t, world ENU (N)."""
    fx = wind[0]
    fy = wind[1]
    fz = wind[2]
    for i in range(gusts.shape[0]):
        t0 = gusts[i, 0]
        dur = gusts[i, 1]
        if t0 <= t < t0 + dur:
            shape = 0.5 * (1.0 - math.cos(2.0 * math.pi * (t - t0) / dur))
            fx += shape * gusts[i, 2]
            fy += shape * gusts[i, 3]
            fz += shape * gusts[i, 4]
    return fx, fy, fz


@jit(nrt=False)
def shock_torque(t, shocks):
    """Body torque (N m, B) of the shocks active at time t: a tip push F along +z_B at p = l e_arm
    gives ``p x F = (p_y F, -p_x F, 0)`` with ``F l = torque``."""
    tx = 0.0
    ty = 0.0
    for i in range(shocks.shape[0]):
        t0 = shocks[i, 0]
        if t0 <= t < t0 + shocks[i, 3]:
            ax, ay = arm_direction(int(shocks[i, 1]) - 1)
            tx += ay * shocks[i, 2]
            ty -= ax * shocks[i, 2]
    return tx, ty


@jit(nrt=False)
def extra_mass_effects(extra, R, g):
    """Added inertia (dIxx, dIyy, dIzz) and gravity torque (tx, ty, tz) in B of the extra masses.

    Gravity in B is ``R_WB^T (0, 0, -m g)``; the torque about the joint is ``p x f``.
    """
    dixx = 0.0
    diyy = 0.0
    dizz = 0.0
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for arm in range(4):
        m = extra[arm, 0]
        if m == 0.0:
            continue
        d = extra[arm, 1]
        ax, ay = arm_direction(arm)
        px = d * ax
        py = d * ay
        md2 = m * d * d
        dixx += m * py * py
        diyy += m * px * px
        dizz += md2
        fx = -m * g * R[2, 0]
        fy = -m * g * R[2, 1]
        fz = -m * g * R[2, 2]
        tx += py * fz
        ty -= px * fz
        tz += px * fy - py * fx
    return dixx, diyy, dizz, tx, ty, tz
