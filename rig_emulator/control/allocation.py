"""Control allocation: inverse of A6 and what gives way when a motor saturates.

A6: ``u1 = F1 + F2 + F3 + F4``, ``u2 = l (F4 - F2)``, ``u3 = l (F1 - F3)``,
``u4 = c (F1 - F2 + F3 - F4)`` with ``c = kM / kF``; (u2, u3, u4) are torques about the
body axes of B (FRD). The controllers produce torques about the axes of the Euler frame
(``Q = R_WB diag(1,-1,-1)``, docs/explanation/conventions.md); :func:`euler_torque_to_body` is the one
place that converts them.

When the exact inverse keeps every motor in ``[0, f_max]`` it is used as is. Otherwise one of
three readings (``control.allocation_priority``, passed as ``priority``: PRIORITY_*) decides what
gives way; in the first two yaw gets what is left:

* ``"attitude"`` (PRIORITY_ATTITUDE; the ideal plant, the emulator's
  table6 study): roll/pitch first (scaled down only if their differential alone exceeds the
  range), then the collective is shifted to fit. Around hover the motors have more room below
  (down to 0) than above (up to ``f_max``), so a saturated roll/pitch command lowers u1.
* ``"thrust"`` (PRIORITY_THRUST; the ``hilms`` rig): Reading of Sec. 3-3, which computes
  u1 in its first step (the altitude law, third row of Eq. 33) and the attitude inputs u2, u3
  last: the collective u1 is kept (clamped to ``[0, 4 f_max]``) and the roll/pitch
  differential is scaled down, direction kept, until every motor fits around it
  (:func:`thrust_first_scale`). docs/explanation/readings.md, "Table 6's altitude".
* ``"clip"`` (PRIORITY_CLIP): no priority at all. Sec. 3-3's firmware computes u1..u4, the four
  motor thrusts through the A6 inverse and each motor's voltage through Eq. 40's inverse; the
  supply (15 V, Fig. 11) caps each motor on its own, so each thrust is clipped to ``[0, f_max]``
  independently. Only the overflow is lost: a saturated pitch command loses part of its torque
  AND part of the collective, and yaw whatever the clipped motors carried. Measured on ``hilms``
  (docs/explanation/readings.md, "Table 6's altitude", the third reading): Table 3's FLC yaw output then
  takes the motors and the FLC loses the helix, so it is available, not the default.
"""

from rig_emulator._jit import jit

SATURATED_ROLL_PITCH = 1
SATURATED_COLLECTIVE = 2
SATURATED_YAW = 4

PRIORITY_ATTITUDE = 0  # control.allocation_priority "attitude"
PRIORITY_THRUST = 1  # "thrust"
PRIORITY_CLIP = 2  # "clip"
PRIORITIES = {"attitude": PRIORITY_ATTITUDE, "thrust": PRIORITY_THRUST, "clip": PRIORITY_CLIP}


@jit(inline="always")
def euler_torque_to_body(tx, ty, tz):
    """``torque_B = diag(1, -1, -1) torque_euler`` (B is FRD, the Euler frame FLU)."""
    return tx, -ty, -tz


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def allocate(u1, u2, u3, u4, arm_length, km_over_kf, f_max, priority, forces):
    """Motor thrusts ``forces[0:4]`` (N) realising (u1..u4) as closely as the limits allow;
    ``priority``: what gives way when saturating, a PRIORITY_* (module docstring).

    Returns a bitmask of SATURATED_* flags (0 when A6 is inverted exactly).
    """
    flags = 0
    a = u3 / (2.0 * arm_length)
    b = u2 / (2.0 * arm_length)
    y = u4 / (4.0 * km_over_kf)
    r1 = a
    r2 = -b
    r3 = -a
    r4 = b
    collective = 0.25 * u1
    e1 = collective + r1 + y
    e2 = collective + r2 - y
    e3 = collective + r3 + y
    e4 = collective + r4 - y
    tol = 1e-9 * f_max  # rounding of the inverse itself is not saturation
    if min(min(e1, e2), min(e3, e4)) >= -tol and max(max(e1, e2), max(e3, e4)) <= f_max + tol:
        forces[0] = _clip(e1, f_max)
        forces[1] = _clip(e2, f_max)
        forces[2] = _clip(e3, f_max)
        forces[3] = _clip(e4, f_max)
        return flags
    if priority == PRIORITY_CLIP:
        return _clip_each(e1, e2, e3, e4, collective, r1, r4, y, tol, f_max, forces)
    hi_rp = max(max(r1, r2), max(r3, r4))
    lo_rp = min(min(r1, r2), min(r3, r4))
    if priority == PRIORITY_THRUST:
        if collective < 0.0:
            collective = 0.0
            flags |= SATURATED_COLLECTIVE
        elif collective > f_max:
            collective = f_max
            flags |= SATURATED_COLLECTIVE
        scale = thrust_first_scale(collective, lo_rp, hi_rp, f_max)
        if scale < 1.0:
            r1 *= scale
            r2 *= scale
            r3 *= scale
            r4 *= scale
            flags |= SATURATED_ROLL_PITCH
    else:
        span = hi_rp - lo_rp
        if span > f_max:
            scale = f_max / span
            r1 *= scale
            r2 *= scale
            r3 *= scale
            r4 *= scale
            hi_rp *= scale
            lo_rp *= scale
            flags |= SATURATED_ROLL_PITCH
        lo_c = -lo_rp
        hi_c = f_max - hi_rp
        if collective < lo_c:
            collective = lo_c
            flags |= SATURATED_COLLECTIVE
        elif collective > hi_c:
            collective = hi_c
            flags |= SATURATED_COLLECTIVE
    base1 = collective + r1
    base2 = collective + r2
    base3 = collective + r3
    base4 = collective + r4
    # yaw: motors 1, 3 get +y, motors 2, 4 get -y; largest s in [0, 1] keeping all in range
    s = 1.0
    s = _yaw_scale(base1, y, f_max, s)
    s = _yaw_scale(base2, -y, f_max, s)
    s = _yaw_scale(base3, y, f_max, s)
    s = _yaw_scale(base4, -y, f_max, s)
    if s < 1.0:
        flags |= SATURATED_YAW
    forces[0] = _clip(base1 + s * y, f_max)
    forces[1] = _clip(base2 - s * y, f_max)
    forces[2] = _clip(base3 + s * y, f_max)
    forces[3] = _clip(base4 - s * y, f_max)
    return flags


@jit(inline="always")
def _clip_each(e1, e2, e3, e4, collective, r1, r4, y, tol, f_max, forces):
    """The "clip" reading: each motor clipped to [0, f_max] on its own; the flags name what the
    clipped thrusts no longer realise (collective, roll/pitch differential: ``r1`` = u3 / 2l and
    ``r4`` = u2 / 2l per motor, yaw)."""
    f1 = _clip(e1, f_max)
    f2 = _clip(e2, f_max)
    f3 = _clip(e3, f_max)
    f4 = _clip(e4, f_max)
    forces[0] = f1
    forces[1] = f2
    forces[2] = f3
    forces[3] = f4
    flags = 0
    if abs(0.25 * (f1 + f2 + f3 + f4) - collective) > tol:
        flags |= SATURATED_COLLECTIVE
    # per-motor roll/pitch parts: a = (f1 - f3) / 2 (u3), b = (f4 - f2) / 2 (u2)
    if abs(0.5 * (f1 - f3) - r1) > tol or abs(0.5 * (f4 - f2) - r4) > tol:
        flags |= SATURATED_ROLL_PITCH
    if abs(0.25 * (f1 - f2 + f3 - f4) - y) > tol:
        flags |= SATURATED_YAW
    return flags


@jit(inline="always")
def thrust_first_scale(collective, lo_rp, hi_rp, f_max):
    """The largest factor in [0, 1] on the roll/pitch differential (per-motor parts between
    ``lo_rp`` and ``hi_rp``, N) that keeps every motor of a collective ``collective`` (N per
    motor, already in [0, f_max]) inside [0, f_max]: the allocation's "thrust" priority.

    Size: at hover on the HILMS (m g / 4 = 5.47 N, f_max = 714 gr.F = 7.00 N: Eq. 40 at the
    15 V of Fig. 11) a pitch torque of 1.68 N m (3 d1_u3, Table 3's saturated FLC output) asks
    +-3.0 N on motors 1 and 3; the 1.53 N of room above hover scales it by 0.51 (0.86 N m)
    where the "attitude" priority keeps 1.68 N m and lowers u1 from 21.9 N to 16.0 N.
    """
    s = 1.0
    if hi_rp > 0.0 and collective + hi_rp > f_max:
        s = min(s, (f_max - collective) / hi_rp)
    if lo_rp < 0.0 and collective + lo_rp < 0.0:
        s = min(s, -collective / lo_rp)
    return max(0.0, s)


@jit(inline="always")
def _yaw_scale(base, dy, f_max, s):
    if dy > 0.0 and base + s * dy > f_max:
        return max(0.0, (f_max - base) / dy)
    if dy < 0.0 and base + s * dy < 0.0:
        return max(0.0, -base / dy)
    return s


@jit(inline="always")
def _clip(f, f_max):
    if f < 0.0:
        return 0.0
    if f > f_max:
        return f_max
    return f
