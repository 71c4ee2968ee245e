"""Motors: voltage command -> first-order lag -> thrust (Eq. 40), rotor speed and moment (Eq. 38-39).

Eq. 40, measured on the rig: ``F = 47.62 V`` gram-force. The conversion factor to newtons
is applied once when the parameters are packed (``k_v`` in N/V, ``f_ceiling`` in N), so
everything here is SI. Reading: the lag acts on the effective voltage (time constant
``tau_motor``); the thrust follows it through Eq. 40 and is capped at the 850 gr.F ceiling
of Sec. 3-2.
"""

import math

from rig_emulator._jit import jit

GRAM_FORCE_N = 9.80665e-3  # one gram-force in newtons


@jit
def thrust_from_voltage(v, k_v, f_ceiling):
    """Eq. 40 with the supply floor (no negative thrust) and the thrust ceiling."""
    f = k_v * v
    if f < 0.0:
        return 0.0
    if f > f_ceiling:
        return f_ceiling
    return f


@jit
def voltage_for_thrust(f, k_v, v_max):
    """Inverse of Eq. 40 as the motor driver applies it: clipped to the 0..v_max supply."""
    v = f / k_v
    if v < 0.0:
        return 0.0
    if v > v_max:
        return v_max
    return v


@jit
def rotor_speed(f, kf):
    """Rotor speed from F = kF Omega^2 (Eq. 38), rad/s."""
    if f <= 0.0:
        return 0.0
    return math.sqrt(f / kf)
