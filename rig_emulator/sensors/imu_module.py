"""Error model and compiled sampler of the rig's five 9-axis IMU modules (paper Sec. 4-1).

Each module carries an MPU6050 (gyro + accelerometer) and an HMC5883L-class
magnetometer. What each sensor measures (the rig rotates about the joint at the origin,
it does not translate; the translation is virtual and invisible to the sensors):

* gyro: ``omega_B``;
* accelerometer at its mounting point ``p_B``: the specific force
  ``f_B = R_WB^T [0, 0, g] + omega_dot_B x p_B + omega_B x (omega_B x p_B)``
  (level and still: ``f_B = [0, 0, -g]``, B = FRD);
* magnetometer: ``m_B = R_WB^T m_W`` distorted by the frame's soft iron and offset by
  hard iron.

Per module and sensor ``s`` (0 gyro, 1 accel, 2 mag) the output before the ADC is
``y = A_s x + o_s + w_s + n`` with ``A_s = diag(1 + scale) (I + cross) R_SB`` (for the
magnetometer also ``... R_SB S_soft``), ``R_SB`` the module's mounting misalignment,
``o_s`` the turn-on offset / hard iron, ``w_s`` a bias random walk and ``n`` white noise
of sigma ``density * sqrt(bandwidth)``. The ADC quantises to ``round(y / LSB)`` and
saturates at the signed range (16 bit gyro/accel, LSB = full scale / 32768; the
magnetometer's 12-bit output -2048..2047 at its gain, 1090 LSB/Ga at +-1.3 Ga).

Reading (datasheet bounds -> draws): turn-on offsets, scale-factor and cross-axis errors,
hard and soft iron are drawn once per module as normal variables with sigma = bound / 3,
clipped at the bound; the misalignment is a rotation vector with normal components whose
total rms is ``misalignment_deg_rms``. Nonlinearity (0.2 %/0.5 %), temperature drift and
the gyro's g-sensitivity are not modelled.

Raw layout: ``raw_out`` is float64 ``(n_modules, 9)`` holding integer counts:
``[gx, gy, gz, ax, ay, az, mx, my, mz]`` in the module's own (nominally FRD) axes.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.sensors.faults import FAULT_BIAS, FAULT_DEAD, FAULT_NOISE, FAULT_STUCK
from rig_emulator.sensors.presets import load_sensor_preset

GYRO = 0
ACCEL = 1
MAG = 2
GAUSS_T = 1e-4  # tesla per gauss
G0 = 9.80665  # standard gravity, only for datasheet mg / ug figures
HMC5883L_GAIN_LSB_PER_GA = {0.88: 1370.0, 1.3: 1090.0, 1.9: 820.0, 2.5: 660.0,
                            4.0: 440.0, 4.7: 390.0, 5.6: 330.0, 8.1: 230.0}

ImuKernel = namedtuple(
    "ImuKernel",
    [
        "n_modules",       # int
        "decim_inertial",  # int: gyro/accel sampled when step % decim_inertial == 0
        "decim_mag",       # int
        "dt_s",            # physics step [s]
        "pos_B",           # (n, 3) mounting points [m], body FRD
        "err_matrix",      # (n, 3, 3, 3) A_s per module and sensor
        "offset",          # (n, 3, 3) turn-on offset / hard iron, SI (rad/s, m/s^2, T)
        "noise_sigma",     # (3,) white noise per sample, SI
        "walk_sigma",      # (3,) bias random-walk increment per magnetometer period, SI
        "lsb",             # (3,) SI per count
        "count_min",       # (3,)
        "count_max",       # (3,)
        "gravity_m_s2",    # float
        "earth_field_W",   # (3,) T, ENU
    ],
)


@dataclass(frozen=True)
class ImuModulesTruth:
    """The injected per-module errors (what calibration must recover) and the kernel.

    Arrays are indexed ``[module, sensor, ...]`` with sensor 0 gyro, 1 accel, 2 mag.
    """

    positions_B: np.ndarray      # (n, 3) m
    misalignment: np.ndarray     # (n, 3, 3) R_SB
    scale: np.ndarray            # (n, 3, 3) fractional scale-factor error per axis
    cross: np.ndarray            # (n, 3, 3, 3) cross-axis matrix (zero diagonal)
    soft_iron: np.ndarray        # (n, 3, 3) symmetric, near identity
    offset_si: np.ndarray        # (n, 3, 3) turn-on offsets / hard iron, SI
    error_matrix: np.ndarray     # (n, 3, 3, 3) A_s
    kernel: ImuKernel


def load_imu_config(overrides: dict | None = None) -> dict:
    """Datasheet defaults of the module array; ``overrides`` keyed by preset name.

    Example: ``load_imu_config({"mpu6050": {"gyro": {"full_scale_dps": 500}}})``.
    """
    overrides = overrides or {}
    unknown = set(overrides) - {"mpu6050", "hmc5883l", "imu_array"}
    if unknown:
        raise ValueError(f"imu config overrides: unknown preset(s) {sorted(unknown)}; use mpu6050, hmc5883l, imu_array")
    cfg = {name: load_sensor_preset(name, overrides.get(name)) for name in ("mpu6050", "hmc5883l", "imu_array")}
    n = cfg["imu_array"]["array"]["n_modules"]
    rows = len(cfg["imu_array"]["array"]["positions_m"])
    if rows != n:
        raise ValueError(f"imu_array: array.positions_m has {rows} rows: must have array.n_modules = {n}")
    return cfg


def earth_field_enu(site: dict) -> np.ndarray:
    """Earth field in W = ENU [T] from total intensity, inclination (down +) and declination (east +)."""
    total = site["earth_field_uT"] * 1e-6
    inc = math.radians(site["inclination_deg"])
    dec = math.radians(site["declination_deg"])
    h = total * math.cos(inc)
    return np.array([h * math.sin(dec), h * math.cos(dec), -total * math.sin(inc)])


def _bounded_normal(rng: np.random.Generator, bound: float, size) -> np.ndarray:
    return np.clip(rng.normal(0.0, bound / 3.0, size), -bound, bound)


def rotation_from_vector(r: np.ndarray) -> np.ndarray:
    """Rodrigues: the rotation matrix of rotation vector ``r`` [rad] (Python side)."""
    angle = float(np.linalg.norm(r))
    if angle < 1e-15:
        return np.eye(3)
    k = r / angle
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def sensor_scaling(cfg: dict) -> dict:
    """Nominal LSB (SI per count), count range and per-sample noise sigma of each sensor."""
    gyro, accel, mag = cfg["mpu6050"]["gyro"], cfg["mpu6050"]["accel"], cfg["hmc5883l"]["mag"]
    g = cfg["imu_array"]["site"]["gravity_m_s2"]
    gain = HMC5883L_GAIN_LSB_PER_GA[mag["full_scale_gauss"]]
    return {
        "lsb": np.array([math.radians(gyro["full_scale_dps"]) / 32768.0,
                         accel["full_scale_g"] * g / 32768.0,
                         GAUSS_T / gain]),
        "count_min": np.array([-32768.0, -32768.0, -2048.0]),
        "count_max": np.array([32767.0, 32767.0, 2047.0]),
        "noise_sigma": np.array([
            math.radians(gyro["noise_dps_per_rthz"]) * math.sqrt(gyro["noise_bandwidth_hz"]),
            accel["noise_ug_per_rthz"] * 1e-6 * G0 * math.sqrt(accel["noise_bandwidth_hz"]),
            mag["noise_mgauss"] * 1e-3 * GAUSS_T,
        ]),
        "walk_density": np.array([math.radians(gyro["bias_walk_dps_per_rts"]),
                                  accel["bias_walk_ug_per_rts"] * 1e-6 * G0,
                                  mag["bias_walk_mgauss_per_rts"] * 1e-3 * GAUSS_T]),
    }


def draw_imu_modules(cfg: dict, rng: np.random.Generator, physics_dt_s: float = 1e-3) -> ImuModulesTruth:
    """Draw every module's turn-on errors once from ``rng`` (fixed draw order) -> truth + kernel."""
    if not (physics_dt_s > 0.0 and math.isfinite(physics_dt_s)):
        raise ValueError(f"physics_dt_s = {physics_dt_s!r}: must be a positive number of seconds")
    arr, samp, site = cfg["imu_array"]["array"], cfg["imu_array"]["sampling"], cfg["imu_array"]["site"]
    gyro, accel, mag = cfg["mpu6050"]["gyro"], cfg["mpu6050"]["accel"], cfg["hmc5883l"]["mag"]
    n = arr["n_modules"]
    sc = sensor_scaling(cfg)
    mis = np.zeros((n, 3, 3))
    scale = np.zeros((n, 3, 3))
    cross = np.zeros((n, 3, 3, 3))
    soft = np.zeros((n, 3, 3))
    offset = np.zeros((n, 3, 3))
    A = np.zeros((n, 3, 3, 3))
    g = site["gravity_m_s2"]
    off_bounds = [
        np.full(3, math.radians(gyro["zero_rate_offset_dps"])),
        np.array([accel["zero_g_offset_xy_mg"], accel["zero_g_offset_xy_mg"], accel["zero_g_offset_z_mg"]]) * 1e-3 * G0,
        np.full(3, mag["hard_iron_gauss"] * GAUSS_T),
    ]
    tolerances = [(gyro["scale_tolerance"], gyro["cross_axis"]), (accel["scale_tolerance"], accel["cross_axis"]),
                  (mag["scale_tolerance"], mag["cross_axis"])]
    off_diag = ~np.eye(3, dtype=bool)
    for m in range(n):
        rvec = rng.normal(0.0, math.radians(arr["misalignment_deg_rms"]) / math.sqrt(3.0), 3)
        mis[m] = rotation_from_vector(rvec)
        for s in range(3):
            offset[m, s] = np.clip(rng.normal(0.0, off_bounds[s] / 3.0), -off_bounds[s], off_bounds[s])
            scale[m, s] = _bounded_normal(rng, tolerances[s][0], 3)
            cross[m, s][off_diag] = _bounded_normal(rng, tolerances[s][1], 6)
            A[m, s] = np.diag(1.0 + scale[m, s]) @ (np.eye(3) + cross[m, s]) @ mis[m]
        e = _bounded_normal(rng, mag["soft_iron"], (3, 3))
        soft[m] = np.eye(3) + 0.5 * (e + e.T)
        A[m, MAG] = A[m, MAG] @ soft[m]
    dt_mag = samp["mag_decimation"] * physics_dt_s
    kernel = ImuKernel(
        n_modules=n,
        decim_inertial=samp["gyro_accel_decimation"],
        decim_mag=samp["mag_decimation"],
        dt_s=float(physics_dt_s),
        pos_B=np.ascontiguousarray(np.array(arr["positions_m"], dtype=np.float64)),
        err_matrix=np.ascontiguousarray(A),
        offset=np.ascontiguousarray(offset),
        noise_sigma=sc["noise_sigma"],
        # Reading: every bias random walk steps at the magnetometer period (the slowest sensor),
        # with the increment sized for that period: the same walk statistics for a third of the draws.
        walk_sigma=sc["walk_density"] * np.sqrt(dt_mag),
        lsb=sc["lsb"],
        count_min=sc["count_min"],
        count_max=sc["count_max"],
        gravity_m_s2=float(g),
        earth_field_W=earth_field_enu(site),
    )
    return ImuModulesTruth(kernel.pos_B, mis, scale, cross, soft, offset, A, kernel)


@jit(inline="always")
def _emit(A, offset, walk, sig, inv_lsb, lo, hi, m, s, x0, x1, x2, mode, magnitude, rng, raw_out):
    """One sensor triad of module ``m``: error model, noise, ADC, fault, into raw_out."""
    for i in range(3):
        y = (A[m, s, i, 0] * x0 + A[m, s, i, 1] * x1 + A[m, s, i, 2] * x2
             + offset[m, s, i] + walk[m, s, i] + sig * rng.standard_normal())
        if mode == FAULT_NOISE:
            y += magnitude * sig * rng.standard_normal()
        c = math.floor(y * inv_lsb + 0.5)
        if mode == FAULT_BIAS:
            c += magnitude
        if mode == FAULT_DEAD:
            c = 0.0
        if c < lo:
            c = lo
        elif c > hi:
            c = hi
        raw_out[m, 3 * s + i] = c


@jit
def sample_imu_modules(q, omega_B, omega_dot_B, do_inertial, do_mag, k, walk, fault_mode, fault_magnitude,
                       rng, raw_out):
    """Sample every module's gyro+accel (if ``do_inertial``) and magnetometer (if ``do_mag``).

    ``q`` the quaternion of R_WB (scalar first), ``omega_B``/``omega_dot_B`` body rates and
    accelerations (B = FRD). ``walk`` (n, 3, 3) is the bias random-walk state, updated in
    place. A module in the stuck fault keeps its previous raw values. Writes ``raw_out``.

    Callable from Python (it keeps numba's reference counting, which releases the ``rng``
    it unboxes); the step loop calls :func:`_sample_imu_modules`, the same without it
    (``rig_emulator/_jit.py``).
    """
    _sample_imu_modules(q, omega_B, omega_dot_B, np.zeros(6), np.zeros(3), do_inertial, do_mag, k, walk, fault_mode,
                        fault_magnitude, rng, raw_out)


# a call, not inline="always": it has two call sites (the step loop through sensors_step, and
# sample_imu_modules for the calibration); inlined, it was typed twice, which cost about 12 % of the
# cold compile for about 0.1 us a step (python -m benchmarks --only hardware-rig)
@jit(nrt=False)
def _sample_imu_modules(q, omega_B, omega_dot_B, vib, field_B, do_inertial, do_mag, k, walk, fault_mode,
                        fault_magnitude, rng, raw_out):
    """:func:`sample_imu_modules` without reference counting, for the step loop.

    ``vib`` (6,): the frame vibration every module sees alike (
    :func:`rig_emulator.physics.hardware.frame_vibration_step`): gyro (0:3, rad/s) added to
    ``omega_B``, accelerometer (3:6, m/s^2) added to the specific force; zeros on the ideal plant.
    ``field_B`` (3,): the magnetic field of the motor currents at the modules (
    :func:`rig_emulator.physics.hardware.motor_field_step`), T, added to the Earth's field every
    module measures; zeros on the ideal plant.
    """
    q0 = q[0]
    q1 = q[1]
    q2 = q[2]
    q3 = q[3]
    # rows of R_WB^T are the columns of R_WB
    r00 = 1.0 - 2.0 * (q2 * q2 + q3 * q3)
    r01 = 2.0 * (q1 * q2 - q0 * q3)
    r02 = 2.0 * (q1 * q3 + q0 * q2)
    r10 = 2.0 * (q1 * q2 + q0 * q3)
    r11 = 1.0 - 2.0 * (q1 * q1 + q3 * q3)
    r12 = 2.0 * (q2 * q3 - q0 * q1)
    r20 = 2.0 * (q1 * q3 - q0 * q2)
    r21 = 2.0 * (q2 * q3 + q0 * q1)
    r22 = 1.0 - 2.0 * (q1 * q1 + q2 * q2)
    g = k.gravity_m_s2
    gbx = r20 * g
    gby = r21 * g
    gbz = r22 * g
    mw0 = k.earth_field_W[0]
    mw1 = k.earth_field_W[1]
    mw2 = k.earth_field_W[2]
    mbx = r00 * mw0 + r10 * mw1 + r20 * mw2 + field_B[0]
    mby = r01 * mw0 + r11 * mw1 + r21 * mw2 + field_B[1]
    mbz = r02 * mw0 + r12 * mw1 + r22 * mw2 + field_B[2]
    wx = omega_B[0]
    wy = omega_B[1]
    wz = omega_B[2]
    ax_ = omega_dot_B[0]
    ay_ = omega_dot_B[1]
    az_ = omega_dot_B[2]
    A = k.err_matrix
    off = k.offset
    pos = k.pos_B
    sig = k.noise_sigma
    wsig = k.walk_sigma
    lsb = k.lsb
    lo = k.count_min
    hi = k.count_max
    inv0 = 1.0 / lsb[0]
    inv1 = 1.0 / lsb[1]
    inv2 = 1.0 / lsb[2]
    for m in range(k.n_modules):
        if do_mag:  # bias random walk of all three sensors, at the magnetometer period
            for s in range(3):
                if wsig[s] > 0.0:
                    for i in range(3):
                        walk[m, s, i] += wsig[s] * rng.standard_normal()
        mode = fault_mode[m]
        if mode == FAULT_STUCK:
            continue
        magnitude = fault_magnitude[m]
        if do_inertial:
            px = pos[m, 0]
            py = pos[m, 1]
            pz = pos[m, 2]
            # omega x p, then omega x (omega x p) and omega_dot x p
            cx = wy * pz - wz * py
            cy = wz * px - wx * pz
            cz = wx * py - wy * px
            fx = gbx + (wy * cz - wz * cy) + (ay_ * pz - az_ * py) + vib[3]
            fy = gby + (wz * cx - wx * cz) + (az_ * px - ax_ * pz) + vib[4]
            fz = gbz + (wx * cy - wy * cx) + (ax_ * py - ay_ * px) + vib[5]
            _emit(A, off, walk, sig[0], inv0, lo[0], hi[0], m, 0, wx + vib[0], wy + vib[1], wz + vib[2], mode,
                  magnitude, rng, raw_out)
            _emit(A, off, walk, sig[1], inv1, lo[1], hi[1], m, 1, fx, fy, fz, mode, magnitude,
                  rng, raw_out)
        if do_mag:
            _emit(A, off, walk, sig[2], inv2, lo[2], hi[2], m, 2, mbx, mby, mbz, mode, magnitude,
                  rng, raw_out)
