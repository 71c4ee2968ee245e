"""Per-module IMU calibration by Levenberg-Marquardt (paper Sec. 4-1) and its application.

The paper removes "bias error, scale factor, and axes non-orthogonality" of each module
by Levenberg-Marquardt before averaging. Reading of the procedure, run on the rig itself
(the spherical joint lets the frame take any attitude):

1. **Static holds.** The frame is held still in ``n_orientations`` >= 12 attitudes whose
   gravity directions are spread evenly over the sphere (a Fibonacci lattice; the first is
   the level home pose), ``hold_s`` seconds each; every module's readings are averaged.
2. **Accelerometer:** ``f = T (y - b)`` with ``T`` upper triangular (scale factors and
   non-orthogonality, 6 values) and bias ``b`` (3), fitted so that ``|f| = g`` in every
   hold (``scipy.optimize.least_squares(method='lm')``). ``|f| = g`` cannot see a rotation
   of the triad; the home pose (level by construction of the rig's rest) then fixes the
   triad's tilt: the fitted ``T`` is premultiplied by the smallest rotation that takes the
   home reading to ``[0, 0, -g]`` (B = FRD). A residual misalignment about z_B remains.
3. **Magnetometer:** ellipsoid fit ``m = S (y - h)``, ``S`` symmetric (soft iron, 6) and
   ``h`` hard iron (3), so that ``|m| = |m_W|``, the site's known total intensity (WMM).
4. **Gyro:** the static holds give zero-rate data; then the frame is turned at a known
   constant rate ``rotation_rate_dps`` about each body axis in both senses for
   ``rotation_s`` seconds from the home pose (the joint admits these rotations; the rate
   is the drive's set-point). ``omega = C (y - b)`` with a full 3x3 ``C`` (scale, cross-axis
   and misalignment relative to B) and bias ``b`` fitted to all means by LM.

The result maps raw counts to SI per module and sensor: ``out = G (raw - o)`` with
``G = C * LSB`` (SI per count) and ``o = b / LSB`` (counts); :func:`apply_imu_calibration`
applies it in compiled code.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass, field

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.physics.rotation import quat_from_euler
from rig_emulator.sensors.imu_module import ACCEL, GYRO, MAG, ImuModulesTruth, sample_imu_modules

ImuCalArrays = namedtuple("ImuCalArrays", ["gain", "offset_counts"])  # (n,3,3,3) SI/count, (n,3,3) counts


@dataclass
class ImuCalibration:
    """Calibration of every module: ``out_si[m, s] = gain[m, s] @ (raw[m, 3s:3s+3] - offset_counts[m, s])``.

    ``residual_rms[m, s]``: rms of the fit residual (gyro rad/s, accel m/s^2, mag T).
    """

    gain: np.ndarray
    offset_counts: np.ndarray
    residual_rms: np.ndarray
    procedure: dict = field(default_factory=dict)

    def arrays(self) -> ImuCalArrays:
        return ImuCalArrays(np.ascontiguousarray(self.gain, dtype=np.float64),
                            np.ascontiguousarray(self.offset_counts, dtype=np.float64))


def nominal_calibration(truth: ImuModulesTruth) -> ImuCalibration:
    """Datasheet scaling only (LSB, no bias, no matrix): what an uncalibrated rig uses."""
    k = truth.kernel
    gain = np.zeros((k.n_modules, 3, 3, 3))
    for s in range(3):
        gain[:, s] = np.eye(3) * k.lsb[s]
    return ImuCalibration(gain, np.zeros((k.n_modules, 3, 3)), np.full((k.n_modules, 3), np.nan),
                          {"kind": "nominal datasheet scaling"})


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def apply_imu_calibration(raw, cal, out_si, n_sensors=3):
    """Raw counts (n, 9) -> calibrated SI (n, 3, 3) ``[module, sensor, axis]`` (Sec. 4-1).

    ``n_sensors = 2`` calibrates gyro and accelerometer only (the magnetometer rows keep
    their last values): the step loop does so on samples without a fresh magnetometer reading.
    """
    G = cal.gain
    o = cal.offset_counts
    for m in range(raw.shape[0]):
        for s in range(n_sensors):
            d0 = raw[m, 3 * s] - o[m, s, 0]
            d1 = raw[m, 3 * s + 1] - o[m, s, 1]
            d2 = raw[m, 3 * s + 2] - o[m, s, 2]
            for i in range(3):
                out_si[m, s, i] = G[m, s, i, 0] * d0 + G[m, s, i, 1] * d1 + G[m, s, i, 2] * d2


def calibration_orientations(n: int) -> np.ndarray:
    """``(n, 3)`` Euler angles (phi, theta, psi) of the static holds: level home first, then
    gravity directions on a Fibonacci lattice over the sphere with golden-angle headings."""
    if n < 12:
        raise ValueError(f"imu_calibration.n_orientations = {n}: must be >= 12")
    out = np.zeros((n, 3))
    golden = math.pi * (3.0 - math.sqrt(5.0))
    for i in range(1, n):
        z = 1.0 - 2.0 * (i - 0.5) / (n - 1)          # body-frame direction u of f / g
        r = math.sqrt(max(0.0, 1.0 - z * z))
        u = np.array([r * math.cos(golden * i), r * math.sin(golden * i), z])
        # f_B / g = [-sin(theta), -sin(phi) cos(theta), -cos(phi) cos(theta)]
        theta = math.asin(max(-1.0, min(1.0, -u[0])))
        phi = math.atan2(-u[1], -u[2])
        out[i] = (phi, theta, ((golden * 7 * i) % (2 * math.pi)) - math.pi)
    return out


@jit
def _average_motion(q0, omega_B, n_steps, k, walk, fault_mode, fault_magnitude, rng, raw, sums, counts):
    """Run the sensor model for ``n_steps`` physics steps of a constant-rate rotation from
    ``q0`` (omega_B = 0: a static hold); accumulate raw sums (n, 9) and sample counts (2,)."""
    q = np.empty(4)
    zero = np.zeros(3)
    wn = math.sqrt(omega_B[0] ** 2 + omega_B[1] ** 2 + omega_B[2] ** 2)
    for step in range(n_steps):
        if wn > 0.0:
            half = 0.5 * wn * step * k.dt_s
            c = math.cos(half)
            s = math.sin(half) / wn
            e1 = s * omega_B[0]
            e2 = s * omega_B[1]
            e3 = s * omega_B[2]
            # q = q0 (x) (c, e): rotation about a body axis at constant body rate
            q[0] = q0[0] * c - q0[1] * e1 - q0[2] * e2 - q0[3] * e3
            q[1] = q0[0] * e1 + q0[1] * c + q0[2] * e3 - q0[3] * e2
            q[2] = q0[0] * e2 - q0[1] * e3 + q0[2] * c + q0[3] * e1
            q[3] = q0[0] * e3 + q0[1] * e2 - q0[2] * e1 + q0[3] * c
        else:
            for j in range(4):
                q[j] = q0[j]
        do_i = step % k.decim_inertial == 0
        do_m = step % k.decim_mag == 0
        sample_imu_modules(q, omega_B, zero, do_i, do_m, k, walk, fault_mode, fault_magnitude, rng, raw)
        for m in range(raw.shape[0]):
            if do_i:
                for j in range(6):
                    sums[m, j] += raw[m, j]
            if do_m:
                for j in range(6, 9):
                    sums[m, j] += raw[m, j]
        if do_i:
            counts[0] += 1.0
        if do_m:
            counts[1] += 1.0


def _collect(truth: ImuModulesTruth, rng, walk, q0, omega_B, seconds: float) -> np.ndarray:
    """Mean raw counts (n, 9) of every module over one hold or rotation."""
    k = truth.kernel
    n = k.n_modules
    raw = np.zeros((n, 9))
    sums = np.zeros((n, 9))
    counts = np.zeros(2)
    steps = max(1, int(round(seconds / k.dt_s)))
    _average_motion(q0, np.asarray(omega_B, dtype=np.float64), steps, k, walk,
                    np.zeros(n, dtype=np.int64), np.zeros(n), rng, raw, sums, counts)
    if counts[1] == 0:
        raise ValueError(f"imu_calibration.hold_s = {seconds}: too short for one magnetometer sample")
    sums[:, :6] /= counts[0]
    sums[:, 6:] /= counts[1]
    return sums


def _upper(p):
    return np.array([[p[0], p[1], p[2]], [0.0, p[3], p[4]], [0.0, 0.0, p[5]]])


def _sym(p):
    return np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])


def _fit_norm(y: np.ndarray, matrix, bias0: np.ndarray):
    """LM fit of ``|M(p) (y_i - b)| = 1`` (y normalised by the reference magnitude)."""
    def residual(p):
        M = matrix(p[3:])
        return np.linalg.norm((y - p[:3]) @ M.T, axis=1) - 1.0

    from scipy.optimize import least_squares  # imported when a calibration runs: 0.3-0.5 s off every start

    p0 = np.concatenate([bias0, [1.0, 0.0, 0.0, 1.0, 0.0, 1.0]])  # identity in both layouts
    sol = least_squares(residual, p0, method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    return sol.x[:3], matrix(sol.x[3:]), float(np.sqrt(np.mean(sol.fun ** 2)))


def _rotation_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation taking direction ``a`` onto direction ``b`` (Python side)."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(a @ b)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def calibrate_imu_modules(params: dict, truth: ImuModulesTruth, rng: np.random.Generator,
                          n_orientations: int | None = None) -> ImuCalibration:
    """Run the simulated calibration procedure (module docstring) and fit every module.

    ``params``: the estimation config (``load_estimation_config()``); its
    ``imu_calibration`` table gives the procedure, ``n_orientations`` overrides it.
    ``truth``: the drawn modules to simulate (the fit never reads their errors).
    """
    proc = dict(params["imu_calibration"])
    if n_orientations is not None:
        proc["n_orientations"] = int(n_orientations)
    poses = calibration_orientations(proc["n_orientations"])
    k = truth.kernel
    n = k.n_modules
    g = k.gravity_m_s2
    field_T = float(np.linalg.norm(k.earth_field_W))
    walk = np.zeros((n, 3, 3))
    q = np.zeros(4)
    static = []
    for phi, theta, psi in poses:
        quat_from_euler(phi, theta, psi, q)
        static.append(_collect(truth, rng, walk, q.copy(), np.zeros(3), proc["hold_s"]))
    static = np.array(static)  # (poses, n, 9)
    rate = math.radians(proc["rotation_rate_dps"])
    quat_from_euler(poses[0, 0], poses[0, 1], poses[0, 2], q)
    rotations, rates = [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            w = np.zeros(3)
            w[axis] = sign * rate
            rotations.append(_collect(truth, rng, walk, q.copy(), w, proc["rotation_s"]))
            rates.append(w)
    rotations = np.array(rotations)
    rates = np.array(rates)

    gain = np.zeros((n, 3, 3, 3))
    offset = np.zeros((n, 3, 3))
    resid = np.zeros((n, 3))
    lsb = k.lsb
    for m in range(n):
        # accelerometer: |f| = g, then level alignment on the home pose
        ya = static[:, m, 3:6] * lsb[ACCEL] / g
        b, T, resid[m, ACCEL] = _fit_norm(ya, _upper, np.zeros(3))
        home = T @ (ya[0] - b)
        C = _rotation_onto(home, np.array([0.0, 0.0, -1.0])) @ T
        gain[m, ACCEL] = C * lsb[ACCEL]
        offset[m, ACCEL] = b * g / lsb[ACCEL]
        resid[m, ACCEL] *= g
        # magnetometer: ellipsoid |m| = |m_W|
        ym = static[:, m, 6:9] * lsb[MAG] / field_T
        h, S, resid[m, MAG] = _fit_norm(ym, _sym, ym.mean(axis=0))
        gain[m, MAG] = S * lsb[MAG]
        offset[m, MAG] = h * field_T / lsb[MAG]
        resid[m, MAG] *= field_T
        # gyro: zero-rate holds + known-rate rotations, omega = C (y - b)
        yg = np.concatenate([static[:, m, 0:3], rotations[:, m, 0:3]]) * lsb[GYRO] / rate
        wt = np.concatenate([np.zeros((len(poses), 3)), rates / rate])

        def gyro_residual(p, yg=yg, wt=wt):
            return ((yg - p[:3]) @ p[3:].reshape(3, 3).T - wt).ravel()

        from scipy.optimize import least_squares

        p0 = np.concatenate([yg[: len(poses)].mean(axis=0), np.eye(3).ravel()])
        sol = least_squares(gyro_residual, p0, method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
        gain[m, GYRO] = sol.x[3:].reshape(3, 3) * lsb[GYRO]
        offset[m, GYRO] = sol.x[:3] * rate / lsb[GYRO]
        resid[m, GYRO] = float(np.sqrt(np.mean(sol.fun ** 2))) * rate
    proc["gravity_m_s2"] = g
    proc["earth_field_T"] = field_T
    return ImuCalibration(gain, offset, resid, proc)
