"""Frame conversions between the rig's world (paper) frame and MAVLink's NED/FRD frames.

Implements docs/explanation/conventions.md "Frames":

* World W is ENU (X east, Y north, Z up); MAVLink's local frame is NED. The two differ by
  the permutation ``T_NED_ENU`` (x_N = y_E, y_N = x_E, z_N = -z_E), which is its own inverse.
* Body B is FRD (x forward, y right, z down), Eq. 2:
  ``R_WB = Rz(psi) Ry(theta) Rx(phi) diag(1, -1, -1)``. MAVLink's body frame is also FRD, so
  the attitude MAVLink reports is ``R_NED_FRD = T_NED_ENU @ R_WB``.
* MAVLink's Euler angles (ATTITUDE) are the Z-Y-X angles of ``R_NED_FRD``:
  ``R_NED_FRD = Rz(yaw) Ry(pitch) Rx(roll)``; ATTITUDE_QUATERNION is the same rotation as a
  unit quaternion (w, x, y, z).
* Since ``T_NED_ENU = Rx(pi) Rz(-pi/2)`` and conjugation by Rx(pi) flips the sign of y and z
  rotations, ``R_NED_FRD = Rz(pi/2 - psi) Ry(-theta) Rx(phi)``: roll = phi,
  pitch = -theta, yaw = pi/2 - psi. Paper psi = 0 (body x east) is MAVLink yaw = +pi/2.
* Body rates: omega_B is expressed in B, which is FRD like MAVLink's body frame, so the
  rates (p, q, r) pass unchanged into ATTITUDE.rollspeed/pitchspeed/yawspeed.
"""

from __future__ import annotations

import math

import numpy as np

#: ENU -> NED permutation (also NED -> ENU: it is an involution).
T_NED_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: diag(1, -1, -1): FLU body axes -> FRD body axes (Eq. 2).
D_FLU_FRD = np.diag([1.0, -1.0, -1.0])


def _vectors(v) -> np.ndarray:
    arr = np.asarray(v, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"expected vectors of shape (3,) or (N, 3), got shape {arr.shape}")
    return arr


def enu_to_ned(v) -> np.ndarray:
    """Vectors in ENU (shape (3,) or (N, 3)) to NED: (e, n, u) -> (n, e, -u)."""
    arr = _vectors(v)
    return np.stack([arr[..., 1], arr[..., 0], -arr[..., 2]], axis=-1)


def enu_to_ned_xyz(e: float, n: float, u: float) -> tuple[float, float, float]:
    """One ENU vector as three floats -> NED (n, e, -u) as floats (for per-step messages)."""
    return float(n), float(e), -float(u)


def ned_to_enu(v) -> np.ndarray:
    """Vectors in NED (shape (3,) or (N, 3)) to ENU: (n, e, d) -> (e, n, -d)."""
    arr = _vectors(v)
    return np.stack([arr[..., 1], arr[..., 0], -arr[..., 2]], axis=-1)


def wrap_pi(angle):
    """Wrap angles (rad) to [-pi, pi); floats stay floats, arrays stay arrays."""
    wrapped = np.mod(np.asarray(angle, dtype=float) + np.pi, 2.0 * np.pi) - np.pi
    return float(wrapped) if wrapped.ndim == 0 else wrapped


def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)  # libm's, as np.cos/np.sin of one float (tests/protocol/test_frames_scalar.py)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)  # libm's, as np.cos/np.sin of one float (tests/protocol/test_frames_scalar.py)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)  # libm's, as np.cos/np.sin of one float (tests/protocol/test_frames_scalar.py)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_zyx(z: float, y: float, x: float) -> np.ndarray:
    """Rz(z) @ Ry(y) @ Rx(x): the Z-Y-X (yaw, pitch, roll) rotation matrix."""
    return _rz(z) @ _ry(y) @ _rx(x)


def _zyx_angles(r: np.ndarray) -> tuple[float, float, float]:
    """(x, y, z) angles of R = Rz(z) Ry(y) Rx(x); y in [-pi/2, pi/2], x and z in (-pi, pi]."""
    # libm's atan2 and asin (math's), not numpy's: on hosts with AVX-512 numpy runs its own SIMD kernels,
    # which differ from libm in the last bit for ~6 % of arguments, and the served rig's scalar form
    # (zyx_angles_xyz) must give these numbers to the bit on every host. min/max, not np.clip (~5 us): NaN kept.
    x = math.atan2(float(r[2, 1]), float(r[2, 2]))
    y = -math.asin(min(max(float(r[2, 0]), -1.0), 1.0))
    z = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return x, y, z


def rwb_from_paper_euler(phi: float, theta: float, psi: float) -> np.ndarray:
    """R_WB = Rz(psi) Ry(theta) Rx(phi) diag(1, -1, -1) (Eq. 2)."""
    return rotation_zyx(psi, theta, phi) @ D_FLU_FRD


def paper_euler_from_rwb(r_wb) -> tuple[float, float, float]:
    """(phi, theta, psi): Z-Y-X angles of Q = R_WB diag(1, -1, -1) (docs/explanation/conventions.md)."""
    return _zyx_angles(np.asarray(r_wb, dtype=float) @ D_FLU_FRD)


def rwb_to_r_ned_frd(r_wb) -> np.ndarray:
    """Attitude in MAVLink terms: R_NED_FRD = T_NED_ENU @ R_WB (B is already FRD)."""
    return T_NED_ENU @ np.asarray(r_wb, dtype=float)


def mavlink_euler_from_rwb(r_wb) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of MAVLink ATTITUDE: Z-Y-X angles of R_NED_FRD."""
    return _zyx_angles(rwb_to_r_ned_frd(r_wb))


def quaternion_from_rotation(r) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (Shepperd's method)."""
    r = np.asarray(r, dtype=float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    k = int(np.argmax([trace, r[0, 0], r[1, 1], r[2, 2]]))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif k == 1:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif k == 2:
        s = 2.0 * np.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    q = np.array(q)
    # The squares summed in order, not np.linalg.norm: numpy's norm is BLAS's dot, whose sum order
    # depends on the host's SIMD kernel (AVX-512 pairs the terms), and the scalar form must match it.
    q /= np.sqrt(((0.0 + q[0] * q[0]) + q[1] * q[1]) + q[2] * q[2] + q[3] * q[3])
    return -q if q[0] < 0.0 else q


def mavlink_quaternion_from_rwb(r_wb) -> np.ndarray:
    """ATTITUDE_QUATERNION (w, x, y, z) of R_NED_FRD, w >= 0."""
    return quaternion_from_rotation(rwb_to_r_ned_frd(r_wb))


def _scalar_or_array(x):
    arr = np.asarray(x, dtype=float)
    return float(arr) if arr.ndim == 0 else arr


def _swap_convention(a, b, c):
    """(a, -b, wrap(pi/2 - c)): the map is its own inverse (see the module docstring)."""
    return (
        _scalar_or_array(a),
        _scalar_or_array(-np.asarray(b, dtype=float)),
        _scalar_or_array(wrap_pi(np.pi / 2.0 - np.asarray(c, dtype=float))),
    )


def paper_euler_to_mavlink(phi, theta, psi):
    """Paper (phi, theta, psi) -> MAVLink (roll, pitch, yaw) = (phi, -theta, pi/2 - psi).

    Yaw is wrapped to [-pi, pi). Works on scalars (returns floats) and arrays.
    """
    return _swap_convention(phi, theta, psi)


def mavlink_euler_to_paper(roll, pitch, yaw):
    """MAVLink (roll, pitch, yaw) -> paper (phi, theta, psi) = (roll, -pitch, pi/2 - yaw).

    Psi is wrapped to [-pi, pi). Works on scalars (returns floats) and arrays.
    """
    return _swap_convention(roll, pitch, yaw)


def mavlink_body_rates_from_omega_b(omega_b) -> np.ndarray:
    """(rollspeed, pitchspeed, yawspeed) from omega_B: identical, both frames are FRD."""
    return _vectors(omega_b).copy()


def omega_b_from_mavlink_body_rates(rates) -> np.ndarray:
    """omega_B from MAVLink (rollspeed, pitchspeed, yawspeed): identical, both are FRD."""
    return _vectors(rates).copy()


def rotation_from_quaternion(q) -> np.ndarray:
    """Rotation matrix of a quaternion (w, x, y, z); normalised first (MAVLink sends float32)."""
    w, x, y, z = (float(v) for v in q)
    n = np.sqrt(w * w + x * x + y * y + z * z)
    if not np.isfinite(n) or n == 0.0:
        raise ValueError(f"quaternion {tuple(q)} has no direction")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ])


def mavlink_euler_from_quaternion(q) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a MAVLink attitude quaternion (w, x, y, z) of R_NED_FRD
    (ATTITUDE_QUATERNION, ATTITUDE_TARGET.q): the Z-Y-X angles ATTITUDE reports."""
    return _zyx_angles(rotation_from_quaternion(q))


def mavlink_euler_from_quaternions(q) -> np.ndarray:
    """(N, 3) roll, pitch, yaw of N MAVLink attitude quaternions ((N, 4) w, x, y, z), as
    :func:`mavlink_euler_from_quaternion` row by row (same formulas, in arrays, for a log's
    thousands of rows); rows without a direction (zero, NaN or infinite) are NaN."""
    q = np.asarray(q, dtype=float).reshape(-1, 4)
    n = np.sqrt(np.sum(q * q, axis=1))
    bad = ~np.isfinite(n) | (n == 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        w, x, y, z = (q[:, k] / n for k in range(4))
        r21 = 2.0 * (y * z + w * x)
        r22 = 1.0 - 2.0 * (x * x + y * y)
        r20 = 2.0 * (x * z - w * y)
        r10 = 2.0 * (x * y + w * z)
        r00 = 1.0 - 2.0 * (y * y + z * z)
        out = np.column_stack([np.arctan2(r21, r22), -np.arcsin(np.clip(r20, -1.0, 1.0)), np.arctan2(r10, r00)])
    out[bad] = np.nan
    return out


#: T_NED_ENU as a unit quaternion (w, x, y, z): a half turn about the axis (1, 1, 0) / sqrt(2).
_Q_NED_ENU = (0.0, 0.5 ** 0.5, 0.5 ** 0.5, 0.0)


def mavlink_quaternion_from_quat_wb(q_wb) -> tuple[float, float, float, float]:
    """The MAVLink attitude quaternion (w, x, y, z) of R_NED_FRD = T_NED_ENU R_WB, w >= 0, from
    the rig's quaternion of R_WB (scalar first): the same as :func:`mavlink_quaternion_from_rwb`
    as a quaternion product, without building matrices (for per-step messages)."""
    aw, ax, ay, az = _Q_NED_ENU
    bw, bx, by, bz = map(float, q_wb)
    w = aw * bw - ax * bx - ay * by - az * bz
    x = aw * bx + ax * bw + ay * bz - az * by
    y = aw * by - ax * bz + ay * bw + az * bx
    z = aw * bz + ax * by - ay * bx + az * bw
    n = (w * w + x * x + y * y + z * z) ** 0.5
    if w < 0.0:
        n = -n
    return w / n, x / n, y / n, z / n


# --- scalar forms for the served rig's per-chunk messages -----------------------------
# The functions below give, bit for bit, what the array functions above give for one attitude,
# in plain float arithmetic: a 3x3 matrix is a 9-tuple (row-major). numpy's small-array calls
# cost microseconds each; a served rig builds these messages hundreds of times per simulated
# second. "Bit for bit" holds where the operations are the same IEEE operations in the same
# order: a product with T_NED_ENU is a permutation whose sums start from +0 (as numpy's matmul
# does: a zero entry comes out +0, a NaN or infinity elsewhere in the row still spreads);
# a quaternion's norm is the square root of its squares summed in order (sqrt is correctly
# rounded in numpy and libm alike); the angles are math's atan2 and asin in both forms
# (_zyx_angles). Non-finite entries (a diverged
# simulation) go through the array forms, whose NaNs carry their own sign bits. tests/protocol/test_frames_scalar.py
# checks each against its array form (random attitudes, signed zeros, NaN).


def rwb_from_quaternion_xyz(w: float, x: float, y: float, z: float) -> tuple:
    """R_WB (9-tuple, row-major) of the rig's unit quaternion (scalar first): the formulas of
    :func:`rig_emulator.physics.rotation.quat_to_rot` (what ``RigSnapshot.rotation`` fills)."""
    return (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y))


def rwb_to_r_ned_frd_xyz(r: tuple) -> tuple:
    """:func:`rwb_to_r_ned_frd` of a 9-tuple: T_NED_ENU @ R_WB as numpy's matmul computes it."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = r
    return (((0.0 + 0.0 * r00) + r10) + 0.0 * r20, ((0.0 + 0.0 * r01) + r11) + 0.0 * r21,
            ((0.0 + 0.0 * r02) + r12) + 0.0 * r22,
            ((0.0 + r00) + 0.0 * r10) + 0.0 * r20, ((0.0 + r01) + 0.0 * r11) + 0.0 * r21,
            ((0.0 + r02) + 0.0 * r12) + 0.0 * r22,
            ((0.0 + 0.0 * r00) + 0.0 * r10) + -1.0 * r20, ((0.0 + 0.0 * r01) + 0.0 * r11) + -1.0 * r21,
            ((0.0 + 0.0 * r02) + 0.0 * r12) + -1.0 * r22)


def zyx_angles_xyz(r: tuple) -> tuple[float, float, float]:
    """:func:`_zyx_angles` of a 9-tuple."""
    return (math.atan2(r[7], r[8]), -math.asin(min(max(r[6], -1.0), 1.0)), math.atan2(r[3], r[0]))


def mavlink_euler_from_rwb_xyz(r: tuple) -> tuple[float, float, float]:
    """:func:`mavlink_euler_from_rwb` of R_WB as a 9-tuple."""
    if not math.isfinite(sum(r)):  # NaN or infinite entries (a diverged simulation): the array form's NaNs
        return mavlink_euler_from_rwb(np.array(r).reshape(3, 3))
    return zyx_angles_xyz(rwb_to_r_ned_frd_xyz(r))


def _sqrt(v: float) -> float:
    return math.sqrt(v) if v >= 0.0 else math.nan  # np.sqrt: NaN for a negative or NaN argument


def quaternion_from_rotation_xyz(r: tuple) -> tuple[float, float, float, float]:
    """:func:`quaternion_from_rotation` of a 9-tuple (Shepperd's method, w >= 0)."""
    try:
        return _quaternion_from_rotation_xyz(r)
    except ZeroDivisionError:  # not a rotation (numpy divides by 0 with a warning): the array form's result
        return tuple(quaternion_from_rotation(np.array(r).reshape(3, 3)).tolist())


def _quaternion_from_rotation_xyz(r: tuple) -> tuple[float, float, float, float]:
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = r
    trace = r00 + r11 + r22
    cand = (trace, r00, r11, r22)
    k = next((i for i, c in enumerate(cand) if c != c), None)  # np.argmax: the first NaN, else the first largest
    if k is None:
        k = cand.index(max(cand))
    if k == 0:
        s = 2.0 * _sqrt(1.0 + trace)
        q = (0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s)
    elif k == 1:
        s = 2.0 * _sqrt(1.0 + r00 - r11 - r22)
        q = ((r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s)
    elif k == 2:
        s = 2.0 * _sqrt(1.0 - r00 + r11 - r22)
        q = ((r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s)
    else:
        s = 2.0 * _sqrt(1.0 - r00 - r11 + r22)
        q = ((r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s)
    w, x, y, z = q
    n = _sqrt(((0.0 + w * w) + x * x) + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return (-w, -x, -y, -z) if w < 0.0 else (w, x, y, z)


def mavlink_quaternion_from_rwb_xyz(r: tuple) -> tuple[float, float, float, float]:
    """:func:`mavlink_quaternion_from_rwb` of R_WB as a 9-tuple."""
    if not math.isfinite(sum(r)):  # NaN or infinite entries: the array form's NaNs
        return tuple(mavlink_quaternion_from_rwb(np.array(r).reshape(3, 3)).tolist())
    return quaternion_from_rotation_xyz(rwb_to_r_ned_frd_xyz(r))


def paper_yaw_to_mavlink_xyz(psi: float) -> float:
    """MAVLink yaw of paper psi, wrapped to [-pi, pi): :func:`paper_euler_to_mavlink`'s third
    value for one float (Python's float ``%`` is numpy's ``np.mod``: fmod, then the divisor's sign)."""
    return (math.pi / 2.0 - psi + math.pi) % (2.0 * math.pi) - math.pi
