"""Cascaded PID baseline (the conventional controller the paper compares against, Sec. 1).

Position: desired acceleration ``a = x_des'' + kp e + ki int(e) + kd e'`` per axis, turned
into u1 and (uX, uY) by Eq. 33 and into a desired attitude by Eq. 35 like the other
strategies. Attitude: ``tau = I (x_des'' + kp e + ki int(e) + kd e')`` about the Euler axes.
Integrators are clamped to +-integral_limit (anti-windup).
"""

from rig_emulator._jit import jit


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def pid_axis(e, de, ff, kp, ki, kd, integ, idx, dt, limit):
    """One PID axis; ``integ[idx]`` holds the integral of e. Returns ff + kp e + ki int + kd de."""
    v = integ[idx] + e * dt
    if v > limit:
        v = limit
    elif v < -limit:
        v = -limit
    integ[idx] = v
    return ff + kp * e + ki * v + kd * de
