"""Desired-attitude shaping: the rates and accelerations the attitude laws need.

Eq. 9-10 need phi_des' and phi_des'' (the term Xi). When the desired attitude comes from
the position loop (Eq. 35) it has no analytic derivative; Reading: we pass it through a
critically damped second-order filter (natural frequency 1/tau) and take the filter's
output, rate and acceleration. Yaw is unwrapped against the filter state.
"""

import math

from rig_emulator._jit import jit


@jit(inline="always")
def wrap_angle(a):
    """Angle wrapped to (-pi, pi]."""
    two_pi = 2.0 * math.pi
    a = a - two_pi * math.floor((a + math.pi) / two_pi)
    if a <= -math.pi:
        a += two_pi
    return a


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def reference_step(target, state, i, omega_n, dt, wrap):
    """Advance filter ``i`` (state[2i] = value, state[2i+1] = rate) towards ``target``.

    Returns (value, rate, acceleration). Semi-implicit Euler, stable for omega_n dt < 1.
    """
    r = state[2 * i]
    dr = state[2 * i + 1]
    err = target - r
    if wrap:
        err = wrap_angle(err)
    acc = omega_n * omega_n * err - 2.0 * omega_n * dr
    dr += acc * dt
    r += dr * dt
    if wrap:
        r = wrap_angle(r)
    state[2 * i] = r
    state[2 * i + 1] = dr
    return r, dr, acc
