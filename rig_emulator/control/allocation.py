"""Control allocation: inverse of A6 with saturation that keeps attitude authority first.

A6: ``u1 = F1 + F2 + F3 + F4``, ``u2 = l (F4 - F2)``, ``u3 = l (F1 - F3)``,
``u4 = c (F1 - F2 + F3 - F4)`` with ``c = kM / kF``; (u2, u3, u4) are torques about the
body axes of B (FRD). The controllers produce torques about the axes of the Euler frame
(``Q = R_WB diag(1,-1,-1)``, docs/CONVENTIONS.md); :func:`euler_torque_to_body` is the one
place that converts them.

When the exact inverse keeps every motor in ``[0, f_max]`` it is used as is. Otherwise the
priority is roll/pitch first (scaled down only if
their differential alone exceeds the range), then the collective is shifted to fit, then
yaw gets what is left.
"""

from rig_emulator._jit import jit

SATURATED_ROLL_PITCH = 1
SATURATED_COLLECTIVE = 2
SATURATED_YAW = 4


@jit(inline="always")
def euler_torque_to_body(tx, ty, tz):
    """``torque_B = diag(1, -1, -1) torque_euler`` (B is FRD, the Euler frame FLU)."""
    return tx, -ty, -tz


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile (issue 14)
def allocate(u1, u2, u3, u4, arm_length, km_over_kf, f_max, forces):
    """Motor thrusts ``forces[0:4]`` (N) realising (u1..u4) as closely as the limits allow.

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
    hi_rp = max(max(r1, r2), max(r3, r4))
    lo_rp = min(min(r1, r2), min(r3, r4))
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
