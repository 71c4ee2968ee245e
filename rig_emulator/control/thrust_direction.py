"""Position-to-attitude mapping of Sec. 3-3: Eq. 33 (third row) for u1, Eq. 35 for phi_d, theta_d.

Eq. 33: ``m X'' = uX u1``, ``m Y'' = uY u1``, ``m Z'' = cos(theta) cos(phi) u1 - m g``
(gravity written out). Eq. 34 makes ``(uX, uY, cos theta cos phi)`` the unit thrust
direction, and Eq. 35 inverts it:
``phi_d = asin(uX sin psi_d - uY cos psi_d)``,
``theta_d = asin((uX cos psi_d + uY sin psi_d) / cos phi_d)``.

Singularity guard (Sec. 3-3 notes theta_d is singular at cos phi_d = 0): the horizontal
part ``(uX, uY)`` is clamped to the tilt limit ``sin(max_tilt)``, which keeps both
arguments of asin inside (-1, 1); the clamp is reported through TILT_CLAMPED.
"""

import math

from rig_emulator._jit import jit

TILT_CLAMPED = 8


@jit(inline="always")
def collective_thrust(vertical_force, phi, theta, max_tilt):
    """u1 from the third row of Eq. 33: ``u1 = vertical_force / (cos theta cos phi)``.

    ``vertical_force`` is what the altitude law asks of the vertical thrust component
    (m g plus its correction). The tilt factor is floored at cos(max_tilt).
    """
    c = math.cos(theta) * math.cos(phi)
    floor = math.cos(max_tilt)
    if c < floor:
        c = floor
    u1 = vertical_force / c
    if u1 < 0.0:
        return 0.0
    return u1


@jit(inline="always")
def desired_tilt(ux, uy, psi_d, max_tilt):
    """Eq. 35 with the tilt clamp. Returns (phi_d, theta_d, flags)."""
    flags = 0
    h = math.sqrt(ux * ux + uy * uy)
    h_max = math.sin(max_tilt)
    if h > h_max:
        scale = h_max / h
        ux *= scale
        uy *= scale
        flags |= TILT_CLAMPED
    sp = math.sin(psi_d)
    cp = math.cos(psi_d)
    phi_d = math.asin(ux * sp - uy * cp)
    theta_d = math.asin((ux * cp + uy * sp) / math.cos(phi_d))
    return phi_d, theta_d, flags


@jit
def thrust_direction(phi, theta, psi):
    """Eq. 34: (uX*, uY*, cos theta cos phi) of an attitude, the inverse of Eq. 35."""
    ux = math.sin(psi) * math.sin(phi) + math.cos(psi) * math.sin(theta) * math.cos(phi)
    uy = -math.cos(psi) * math.sin(phi) + math.sin(psi) * math.sin(theta) * math.cos(phi)
    return ux, uy, math.cos(theta) * math.cos(phi)
