"""Reference trajectories: the line-then-helix of Eq. 46 and the harmonic attitude of Eq. 44."""

import math

from rig_emulator._jit import jit


@jit(nrt=False, python=True)  # also called from Python (gcs_tools missions)
def helix_eq46(t, pos, vel, acc):
    """Eq. 46 exactly as published (metres, seconds).

    X = 0 (t < 3), 0.3 (t - 3) (3 <= t < 12), 2.5 cos(0.3 (t - 12)) (t >= 12);
    Y = 0, 0.3 (t - 3), 2.5 sin(0.3 (t - 12)) + 2.5 (same pieces);
    Z = 0 (t < 3), 0.3 (t - 3) (3 <= t < 30), 8 (t >= 30).
    The published X/Y pieces jump at t = 12 (from (2.7, 2.7) to (2.5, 2.5)); kept as published.
    """
    for i in range(3):
        pos[i] = 0.0
        vel[i] = 0.0
        acc[i] = 0.0
    if t >= 3.0 and t < 12.0:
        pos[0] = 0.3 * (t - 3.0)
        pos[1] = 0.3 * (t - 3.0)
        vel[0] = 0.3
        vel[1] = 0.3
    elif t >= 12.0:
        w = 0.3
        a = w * (t - 12.0)
        pos[0] = 2.5 * math.cos(a)
        pos[1] = 2.5 * math.sin(a) + 2.5
        vel[0] = -2.5 * w * math.sin(a)
        vel[1] = 2.5 * w * math.cos(a)
        acc[0] = -2.5 * w * w * math.cos(a)
        acc[1] = -2.5 * w * w * math.sin(a)
    if t >= 3.0 and t < 30.0:
        pos[2] = 0.3 * (t - 3.0)
        vel[2] = 0.3
    elif t >= 30.0:
        pos[2] = 8.0



@jit(nrt=False)
def harmonic_attitude(t, amplitude, omega, att, rate, acc):
    """Eq. 44 on each axis: ``x_des = A sin(omega t)`` with its rate and acceleration."""
    s = math.sin(omega * t)
    c = math.cos(omega * t)
    for i in range(3):
        att[i] = amplitude[i] * s
        rate[i] = amplitude[i] * omega * c
        acc[i] = -amplitude[i] * omega * omega * s
