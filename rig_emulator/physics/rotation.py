"""Attitude math: quaternions, the rotation matrix of Eq. 2, Euler angles, Euler rates.

Conventions (docs/explanation/conventions.md): the state holds the unit quaternion ``q = (w, x, y, z)``
of ``R_WB`` (body B -> world W, B = FRD, W = ENU). The paper's Euler angles are the
Z-Y-X angles of ``Q = R_WB diag(1,-1,-1)``, so that Eq. 2 holds:
``R_WB = Rz(psi) Ry(theta) Rx(phi) diag(1,-1,-1)``.

Everything here is compiled scalar code: no allocation except where a function returns
a fresh matrix for Python-side use (``rwb_from_euler``).
"""

from __future__ import annotations

import math

import numpy as np

from rig_emulator._jit import jit


@jit(nrt=False)
def quat_normalize(q):
    """Normalise a quaternion in place (guards RK4 drift off the unit sphere)."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    q[0] /= n
    q[1] /= n
    q[2] /= n
    q[3] /= n


@jit(nrt=False, python=True)  # also called from Python (live rig, offboard set-points)
def quat_to_rot(q0, q1, q2, q3, R):
    """Rotation matrix of the unit quaternion (q0 scalar) into the 3x3 array ``R``."""
    R[0, 0] = 1.0 - 2.0 * (q2 * q2 + q3 * q3)
    R[0, 1] = 2.0 * (q1 * q2 - q0 * q3)
    R[0, 2] = 2.0 * (q1 * q3 + q0 * q2)
    R[1, 0] = 2.0 * (q1 * q2 + q0 * q3)
    R[1, 1] = 1.0 - 2.0 * (q1 * q1 + q3 * q3)
    R[1, 2] = 2.0 * (q2 * q3 - q0 * q1)
    R[2, 0] = 2.0 * (q1 * q3 - q0 * q2)
    R[2, 1] = 2.0 * (q2 * q3 + q0 * q1)
    R[2, 2] = 1.0 - 2.0 * (q1 * q1 + q2 * q2)


@jit(nrt=False)
def quat_derivative(q0, q1, q2, q3, wx, wy, wz, dq):
    """Quaternion kinematics ``q' = 1/2 q (x) (0, omega_B)`` for body rates ``omega_B``."""
    dq[0] = 0.5 * (-q1 * wx - q2 * wy - q3 * wz)
    dq[1] = 0.5 * (q0 * wx + q2 * wz - q3 * wy)
    dq[2] = 0.5 * (q0 * wy + q3 * wx - q1 * wz)
    dq[3] = 0.5 * (q0 * wz + q1 * wy - q2 * wx)


@jit
def euler_from_quat(q0, q1, q2, q3):
    """The paper's ``(phi, theta, psi)`` from the quaternion of ``R_WB`` (inverse of Eq. 2).

    ``Q = R_WB diag(1,-1,-1)`` is ``R_WB`` times a half turn about x; its quaternion is
    ``q (x) (0, 1, 0, 0) = (-q1, q0, q3, -q2)``, whose Z-Y-X angles are returned.
    """
    a0 = -q1
    a1 = q0
    a2 = q3
    a3 = -q2
    phi = math.atan2(2.0 * (a0 * a1 + a2 * a3), 1.0 - 2.0 * (a1 * a1 + a2 * a2))
    s = 2.0 * (a0 * a2 - a3 * a1)
    if s > 1.0:
        s = 1.0
    elif s < -1.0:
        s = -1.0
    theta = math.asin(s)
    psi = math.atan2(2.0 * (a0 * a3 + a1 * a2), 1.0 - 2.0 * (a2 * a2 + a3 * a3))
    return phi, theta, psi


@jit
def quat_from_euler(phi, theta, psi, q):
    """Quaternion of ``R_WB`` for the paper's Euler angles (Eq. 2), written into ``q``."""
    cr = math.cos(0.5 * phi)
    sr = math.sin(0.5 * phi)
    cp = math.cos(0.5 * theta)
    sp = math.sin(0.5 * theta)
    cy = math.cos(0.5 * psi)
    sy = math.sin(0.5 * psi)
    # quaternion of Q = Rz Ry Rx
    a0 = cy * cp * cr + sy * sp * sr
    a1 = cy * cp * sr - sy * sp * cr
    a2 = cy * sp * cr + sy * cp * sr
    a3 = sy * cp * cr - cy * sp * sr
    # R_WB = Q diag(1,-1,-1): multiply by the half turn about x, (0, 1, 0, 0)
    q[0] = -a1
    q[1] = a0
    q[2] = a3
    q[3] = -a2
    if q[0] < 0.0:  # canonical sign: scalar part non-negative
        q[0] = -q[0]
        q[1] = -q[1]
        q[2] = -q[2]
        q[3] = -q[3]


@jit
def euler_rates_from_body_rates(phi, theta, wx, wy, wz):
    """Euler-angle rates of the paper's angles from body rates ``omega_B`` (B = FRD).

    The Euler angles belong to ``Q = R_WB diag(1,-1,-1)`` whose body rates are
    ``(wx, -wy, -wz)``; the standard Z-Y-X kinematics then give the rates.
    Reading: the paper's A2 writes these with world-frame rates; at small angles both agree.
    """
    p = wx
    qr = -wy
    r = -wz
    sphi = math.sin(phi)
    cphi = math.cos(phi)
    ctheta = math.cos(theta)
    ttheta = math.tan(theta)
    dphi = p + sphi * ttheta * qr + cphi * ttheta * r
    dtheta = cphi * qr - sphi * r
    dpsi = (sphi * qr + cphi * r) / ctheta
    return dphi, dtheta, dpsi


def rwb_from_euler(phi: float, theta: float, psi: float) -> np.ndarray:
    """Eq. 2 written out: ``R_WB = Rz(psi) Ry(theta) Rx(phi) diag(1,-1,-1)`` (Python side)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    cps, sps = math.cos(psi), math.sin(psi)
    return np.array(
        [
            [cps * cth, sps * cph - cps * sth * sph, -sps * sph - cps * sth * cph],
            [sps * cth, -cps * cph - sps * sth * sph, cps * sph - sps * sth * cph],
            [-sth, -cth * sph, -cth * cph],
        ]
    )
