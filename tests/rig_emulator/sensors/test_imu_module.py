"""IMU module error model and sampler (paper Sec. 4-1; RIG-SPEC Sec. 4)."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.physics.rotation import quat_from_euler, rwb_from_euler
from rig_emulator.sensors.faults import FAULT_BIAS, FAULT_DEAD, FAULT_NOISE, FAULT_STUCK
from rig_emulator.sensors.imu_module import (
    ACCEL, GYRO, MAG, draw_imu_modules, earth_field_enu, load_imu_config, sample_imu_modules)


def _ideal(seed=0, **over):
    """Modules with every error and noise switched off (pure physics + quantisation)."""
    o = {"mpu6050": {"gyro": {"zero_rate_offset_dps": 0.0, "scale_tolerance": 0.0, "cross_axis": 0.0,
                              "noise_dps_per_rthz": 0.0, "bias_walk_dps_per_rts": 0.0},
                     "accel": {"zero_g_offset_xy_mg": 0.0, "zero_g_offset_z_mg": 0.0, "scale_tolerance": 0.0,
                               "cross_axis": 0.0, "noise_ug_per_rthz": 0.0, "bias_walk_ug_per_rts": 0.0}},
         "hmc5883l": {"mag": {"scale_tolerance": 0.0, "cross_axis": 0.0, "hard_iron_gauss": 0.0, "soft_iron": 0.0,
                              "noise_mgauss": 0.0}},
         "imu_array": {"array": {"misalignment_deg_rms": 0.0}}}
    for k, tables in over.items():
        for table, values in tables.items():
            o.setdefault(k, {}).setdefault(table, {}).update(values)
    return draw_imu_modules(load_imu_config(o), np.random.default_rng(seed))


def _sample(truth, q, w, wd, mode=None, mag=None, rng=None, raw=None):
    k = truth.kernel
    n = k.n_modules
    raw = np.zeros((n, 9)) if raw is None else raw
    mode = np.zeros(n, dtype=np.int64) if mode is None else mode
    mag = np.zeros(n) if mag is None else mag
    sample_imu_modules(q, np.asarray(w, float), np.asarray(wd, float), True, True, k, np.zeros((n, 3, 3)),
                       mode, mag, rng or np.random.default_rng(1), raw)
    return raw


def test_level_at_rest_reads_minus_g_on_z():
    t = _ideal()
    q = np.zeros(4)
    quat_from_euler(0.0, 0.0, 0.0, q)
    raw = _sample(t, q, [0, 0, 0], [0, 0, 0])
    lsb = t.kernel.lsb
    assert np.allclose(raw[:, 3:6] * lsb[ACCEL], [0.0, 0.0, -9.81], atol=lsb[ACCEL])
    assert np.all(raw[:, 0:3] == 0)


@settings(max_examples=40, deadline=None)
@given(st.floats(-1.2, 1.2), st.floats(-1.2, 1.2), st.floats(-3.1, 3.1),
       st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3), st.lists(st.floats(-20.0, 20.0), min_size=3, max_size=3))
def test_specific_force_gyro_and_field_match_the_physics(phi, theta, psi, w, wd):
    t = _ideal(mpu6050={"gyro": {"full_scale_dps": 2000}, "accel": {"full_scale_g": 16}})
    q = np.zeros(4)
    quat_from_euler(phi, theta, psi, q)
    R = rwb_from_euler(phi, theta, psi)
    raw = _sample(t, q, w, wd)
    k = t.kernel
    w = np.array(w)
    wd = np.array(wd)
    for m in range(k.n_modules):
        p = k.pos_B[m]
        f = R.T @ np.array([0.0, 0.0, 9.81]) + np.cross(wd, p) + np.cross(w, np.cross(w, p))
        assert np.allclose(raw[m, 3:6] * k.lsb[ACCEL], f, atol=0.51 * k.lsb[ACCEL])
        assert np.allclose(raw[m, 0:3] * k.lsb[GYRO], w, atol=0.51 * k.lsb[GYRO])
        m_B = R.T @ earth_field_enu(load_imu_config()["imu_array"]["site"])
        assert np.allclose(raw[m, 6:9] * k.lsb[MAG], m_B, atol=0.51 * k.lsb[MAG])


def test_saturation_and_lsb():
    t = _ideal()
    k = t.kernel
    assert math.isclose(k.lsb[GYRO], math.radians(250) / 32768)
    assert math.isclose(k.lsb[ACCEL], 2 * 9.81 / 32768)
    assert math.isclose(k.lsb[MAG], 1e-4 / 1090)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    raw = _sample(t, q, [10.0, -10.0, 0.0], [0.0, 0.0, 0.0])  # 573 deg/s: beyond +-250
    assert np.all(raw[:, 0] == 32767) and np.all(raw[:, 1] == -32768)


def test_same_seed_is_bit_identical_and_errors_within_datasheet_bounds():
    cfg = load_imu_config()
    a = draw_imu_modules(cfg, np.random.default_rng(7))
    b = draw_imu_modules(cfg, np.random.default_rng(7))
    assert np.array_equal(a.error_matrix, b.error_matrix) and np.array_equal(a.offset_si, b.offset_si)
    assert np.all(np.abs(a.offset_si[:, GYRO]) <= math.radians(20.0))
    assert np.all(np.abs(a.offset_si[:, ACCEL, :2]) <= 0.050 * 9.80665 + 1e-12)
    assert np.all(np.abs(a.offset_si[:, ACCEL, 2]) <= 0.080 * 9.80665 + 1e-12)
    assert np.all(np.abs(a.scale) <= 0.03)
    q = np.array([0.0, 1.0, 0.0, 0.0])
    ra = _sample(a, q, [0.1, 0, 0], [0, 0, 0], rng=np.random.default_rng(3))
    rb = _sample(b, q, [0.1, 0, 0], [0, 0, 0], rng=np.random.default_rng(3))
    assert np.array_equal(ra, rb)


def test_noise_sigma_follows_the_density():
    t = _ideal(mpu6050={"gyro": {"noise_dps_per_rthz": 0.005}, "accel": {"noise_ug_per_rthz": 400.0}})
    k = t.kernel
    q = np.array([0.0, 1.0, 0.0, 0.0])
    rng = np.random.default_rng(2)
    raw = np.zeros((k.n_modules, 9))
    samples = []
    for _ in range(3000):
        _sample(t, q, [0, 0, 0], [0, 0, 0], rng=rng, raw=raw)
        samples.append(raw.copy())
    s = np.array(samples)
    gyro_sigma = s[:, :, 0:3].std(axis=0).mean() * k.lsb[GYRO]
    accel_sigma = s[:, :, 3:6].std(axis=0).mean() * k.lsb[ACCEL]
    assert math.isclose(gyro_sigma, math.radians(0.005) * 16.0, rel_tol=0.05)
    assert math.isclose(accel_sigma, 400e-6 * 9.80665 * math.sqrt(260.0), rel_tol=0.05)


def test_fault_modes():
    t = _ideal(mpu6050={"gyro": {"noise_dps_per_rthz": 0.005}})
    n = t.kernel.n_modules
    q = np.array([0.0, 1.0, 0.0, 0.0])
    raw = _sample(t, q, [0.1, 0.2, 0.3], [0, 0, 0])
    held = raw[1].copy()
    mode = np.array([0, FAULT_STUCK, FAULT_DEAD, FAULT_BIAS, FAULT_NOISE], dtype=np.int64)
    mag = np.array([0.0, 0.0, 0.0, 100.0, 200.0])
    healthy = _sample(t, q, [0.3, 0.2, 0.1], [0, 0, 0], rng=np.random.default_rng(9))
    raw2 = _sample(t, q, [0.3, 0.2, 0.1], [0, 0, 0], mode=mode, mag=mag, rng=np.random.default_rng(9), raw=raw)
    assert np.array_equal(raw2[1], held)
    assert np.all(raw2[2] == 0)
    assert np.allclose(raw2[3] - healthy[3], 100.0, atol=25)  # noise of both draws differs
    assert np.abs(raw2[4, 0:3] - healthy[4, 0:3]).max() > 50   # 200 x 10 counts of extra noise
    assert n == 5
