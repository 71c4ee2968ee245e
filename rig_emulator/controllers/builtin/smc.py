"""Sliding-mode attitude control, Sec. 3-1 (Eq. 5-13) with the model of A3-A5.

Surfaces (Eq. 5): ``s = e' + lambda e`` with ``e = x_des - x`` for x = (phi, theta, psi).
Law (Eq. 9): ``u = b^-1 (-f + Xi + K sw(s))`` with ``Xi = x_des'' + lambda e'`` (Eq. 10),
so that ``s' = -K sw(s)`` on the nominal model and the sliding condition Eq. 4 holds
(``s s' <= -eta |s|``) while K exceeds the model error (Eq. 11-13).

Readings (documented deviations from the printed equations):

* Sign: with ``e = x_des - x`` the reaching term must enter with ``+K`` for Eq. 4 to hold;
  Eq. 9 as printed (``-K sgn(s)``) would push the state away from the surface.
* Model: ``x'' = f(x) + b(x) u`` is derived from Eq. 3 and the Z-Y-X kinematics of the
  paper's angles (rotation.py): with ``omega_Q = diag(1,-1,-1) omega_B``,
  ``x' = W(phi, theta) omega_Q``, ``b = W I^-1`` and
  ``f = W' omega_Q + W diag(1,-1,-1) I^-1 n(omega_B)``,
  ``n = -omega x I omega - omega x Jr (0, 0, Omega_r)``. A2-A5 as printed use world-frame
  rates; both agree near hover. ``u`` is the torque about the Euler-frame axes, turned
  into body torques by ``allocation.euler_torque_to_body``.
* ``sw(s)`` is ``sgn(s)`` (paper-faithful, chatters) or ``sat(s / Phi)`` (boundary layer).
"""

import math

from rig_emulator._jit import jit


@jit(inline="always")
def switch(s, boundary, phi):
    """sgn(s), or sat(s / phi) with a boundary layer."""
    if boundary:
        v = s / phi
        if v > 1.0:
            return 1.0
        if v < -1.0:
            return -1.0
        return v
    if s > 0.0:
        return 1.0
    if s < 0.0:
        return -1.0
    return 0.0


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def smc_attitude(e, de, acc_des, phi, theta, dphi, dtheta, wx, wy, wz, omega_r, cp, s_out, tau_out):
    """Eq. 9 for the three attitude axes.

    ``e``, ``de``, ``acc_des``: (3,) errors, error rates and desired accelerations of
    (phi, theta, psi). ``wx, wy, wz``: body rates (B). ``omega_r``: Eq. 3 rotor term
    estimate. ``cp``: ControlParams (nominal model, gains). Writes surfaces into ``s_out``
    and Euler-frame torques into ``tau_out``.
    """
    # v = Xi + K sw(s)
    v0 = 0.0
    v1 = 0.0
    v2 = 0.0
    for i in range(3):
        s = de[i] + cp.smc_lam[i] * e[i]
        s_out[i] = s
        xi = acc_des[i] + cp.smc_lam[i] * de[i]
        v = xi + cp.smc_k[i] * switch(s, cp.smc_boundary, cp.smc_phi)
        if i == 0:
            v0 = v
        elif i == 1:
            v1 = v
        else:
            v2 = v
    sph = math.sin(phi)
    cph = math.cos(phi)
    sth = math.sin(theta)
    cth = math.cos(theta)
    tth = sth / cth
    # Euler-frame body rates (the roll rate wx does not enter W' omega_Q)
    q = -wy
    r = -wz
    # W' omega_Q with W = [[1, s t, c t], [0, c, -s], [0, s/c, c/c]] (phi, theta)
    wd0 = (cph * tth * q - sph * tth * r) * dphi + (sph * q + cph * r) / (cth * cth) * dtheta
    wd1 = (-sph * q - cph * r) * dphi
    wd2 = (cph * q - sph * r) / cth * dphi + (sph * q + cph * r) * tth / cth * dtheta
    # W^-1 (v - W' omega_Q): Euler accelerations -> Euler-frame angular accelerations
    a0 = v0 - wd0
    a1 = v1 - wd1
    a2 = v2 - wd2
    al0 = a0 - sth * a2
    al1 = cph * a1 + sph * cth * a2
    al2 = -sph * a1 + cph * cth * a2
    # n(omega_B) with the nominal inertia, then D n
    jr = cp.rotor_inertia * omega_r
    nx = -(wy * cp.izz * wz - wz * cp.iyy * wy + wy * jr)
    ny = -(wz * cp.ixx * wx - wx * cp.izz * wz - wx * jr)
    nz = -(wx * cp.iyy * wy - wy * cp.ixx * wx)
    tau_out[0] = cp.ixx * al0 - nx
    tau_out[1] = cp.iyy * al1 + ny
    tau_out[2] = cp.izz * al2 + nz
