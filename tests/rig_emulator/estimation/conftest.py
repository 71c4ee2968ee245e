"""A closed test harness for the estimation chain (no dependency on the rig loop).

A synthetic attitude trajectory (harmonic roll/pitch/yaw at hover-like rates) drives the
sensor model; its quaternion is integrated (RK4 on ``quat_derivative``) from the exact
body rates of the Euler trajectory; the chain calibration -> ensemble -> complementary
filter estimates the attitude, and the errors against the truth are returned.
"""

import math

import numpy as np
import pytest

from rig_emulator._jit import jit
from rig_emulator.estimation.attitude_pipeline import attitude_estimation_step, make_attitude_chain
from rig_emulator.estimation.complementary import complementary_params
from rig_emulator.estimation.ensemble import ensemble_params
from rig_emulator.estimation.estimation_config import load_estimation_config
from rig_emulator.estimation.imu_calibration import calibrate_imu_modules, nominal_calibration
from rig_emulator.physics.rotation import quat_derivative, quat_from_euler, quat_normalize
from rig_emulator.sensors.faults import set_fault
from rig_emulator.sensors.imu_module import draw_imu_modules, load_imu_config
from rig_emulator.sensors.load_cell import draw_load_cells, load_load_cell_config
from rig_emulator.sensors.sensor_step import allocate_raw, make_sensor_suite, sensors_step


@jit
def euler_truth(t, amp, w, psi0, out):
    """Euler angles, their rates and omega_B (FRD) of the harmonic trajectory at ``t``."""
    phi = amp[0] * math.sin(w * t)
    theta = amp[1] * math.sin(w * t + 1.0)
    psi = psi0 + amp[2] * math.sin(0.5 * w * t + 2.0)
    dphi = amp[0] * w * math.cos(w * t)
    dtheta = amp[1] * w * math.cos(w * t + 1.0)
    dpsi = amp[2] * 0.5 * w * math.cos(0.5 * w * t + 2.0)
    # FLU body rates of Q = Rz Ry Rx, then FRD: omega_B = (p, -q, -r)
    p = dphi - math.sin(theta) * dpsi
    q = math.cos(phi) * dtheta + math.sin(phi) * math.cos(theta) * dpsi
    r = -math.sin(phi) * dtheta + math.cos(phi) * math.cos(theta) * dpsi
    out[0] = phi
    out[1] = theta
    out[2] = psi
    out[3] = p
    out[4] = -q
    out[5] = -r


@jit
def run_chain(n_steps, dt, amp, w, psi0, suite, sstate, rng, chain, work, imu_raw, cell_raw,
              fault_step, fault_module, fault_mode, fault_magnitude, est_out, truth_out, q_out, health_out):
    tr = np.zeros(6)
    tr2 = np.zeros(6)
    q = np.zeros(4)
    dq = np.zeros(4)
    k1 = np.zeros(4)
    k2 = np.zeros(4)
    k3 = np.zeros(4)
    qt = np.zeros(4)
    wd = np.zeros(3)
    thrust = np.full(4, 5.47)
    speed = np.full(4, 640.0)
    att = np.zeros(6)
    euler_truth(0.0, amp, w, psi0, tr)
    quat_from_euler(tr[0], tr[1], tr[2], q)
    h = 1e-4
    for k in range(n_steps):
        t = k * dt
        if k == fault_step:
            sstate.imu_fault_mode[fault_module] = fault_mode
            sstate.imu_fault_magnitude[fault_module] = fault_magnitude
        euler_truth(t, amp, w, psi0, tr)
        euler_truth(t + h, amp, w, psi0, tr2)
        for i in range(3):
            wd[i] = (tr2[3 + i] - tr[3 + i]) / h
        mask = sensors_step(k, q, tr[3:6], wd, thrust, speed, suite, sstate, rng, imu_raw, cell_raw)
        health_out[k] = attitude_estimation_step(mask, imu_raw, chain, work, att)
        for i in range(6):
            est_out[k, i] = att[i]
            truth_out[k, i] = tr[i]
        for i in range(4):
            q_out[k, i] = q[i]
        # RK4 of the quaternion kinematics over [t, t + dt] with the exact body rates
        euler_truth(t, amp, w, psi0, tr2)
        quat_derivative(q[0], q[1], q[2], q[3], tr2[3], tr2[4], tr2[5], k1)
        euler_truth(t + 0.5 * dt, amp, w, psi0, tr2)
        for i in range(4):
            qt[i] = q[i] + 0.5 * dt * k1[i]
        quat_derivative(qt[0], qt[1], qt[2], qt[3], tr2[3], tr2[4], tr2[5], k2)
        for i in range(4):
            qt[i] = q[i] + 0.5 * dt * k2[i]
        quat_derivative(qt[0], qt[1], qt[2], qt[3], tr2[3], tr2[4], tr2[5], k3)
        euler_truth(t + dt, amp, w, psi0, tr2)
        for i in range(4):
            qt[i] = q[i] + dt * k3[i]
        quat_derivative(qt[0], qt[1], qt[2], qt[3], tr2[3], tr2[4], tr2[5], dq)
        for i in range(4):
            q[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + dq[i])
        quat_normalize(q)


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


class ChainResult:
    def __init__(self, est, truth, q, health, dt, settle_s):
        self.est, self.truth, self.q, self.health = est, truth, q, health
        s = int(settle_s / dt)
        err = _wrap(est[s:, :3] - truth[s:, :3])
        self.err_deg = np.degrees(err)
        self.rms_deg = np.sqrt(np.mean(self.err_deg ** 2, axis=0))   # per axis phi, theta, psi
        self.rms_total_deg = float(np.sqrt(np.mean(self.err_deg ** 2)))
        self.rate_err = est[s:, 3:] - truth[s:, 3:]


@pytest.fixture(scope="session")
def chain_setup():
    """Modules, cells, calibration drawn once per test session (seed 11)."""
    rng = np.random.default_rng(11)
    imu = draw_imu_modules(load_imu_config(), rng)
    cells = draw_load_cells(load_load_cell_config(), rng)
    est = load_estimation_config()
    cal = calibrate_imu_modules(est, imu, np.random.default_rng(12))
    return {"imu": imu, "cells": cells, "est": est, "cal": cal}


@pytest.fixture(scope="session")
def run_attitude(chain_setup):
    """``run_attitude(amp_deg=(10, 8, 15), duration=30, calibrated=True, mode="robust_mean",
    fault=None | (module, mode_name, magnitude, at_s), seed=5) -> ChainResult``."""

    def run(amp_deg=(10.0, 8.0, 15.0), w=0.4, psi0_deg=30.0, duration=30.0, calibrated=True,
            mode="robust_mean", fault=None, seed=5, settle_s=5.0):
        imu, cells = chain_setup["imu"], chain_setup["cells"]
        est = load_estimation_config({"ensemble": {"mode": mode}})
        suite, sstate = make_sensor_suite(imu, cells)
        imu_raw, cell_raw = allocate_raw(suite)
        cal = chain_setup["cal"] if calibrated else nominal_calibration(imu)
        k = suite.imu
        dt = k.dt_s
        cf = complementary_params(est, k.decim_inertial * dt, k.decim_mag * dt, k.gravity_m_s2)
        chain, work = make_attitude_chain(cal.arrays(), ensemble_params(est), cf, k.n_modules)
        n = int(round(duration / dt))
        est_out = np.zeros((n, 6))
        truth_out = np.zeros((n, 6))
        q_out = np.zeros((n, 4))
        health = np.zeros(n, dtype=np.int64)
        fault_step, fmod, fmode, fmag = -1, 0, 0, 0.0
        if fault is not None:
            modes = np.zeros(k.n_modules, dtype=np.int64)
            mags = np.zeros(k.n_modules)
            set_fault(modes, mags, fault[0], fault[1], fault[2], imu=True)
            fault_step, fmod, fmode, fmag = int(fault[3] / dt), fault[0], int(modes[fault[0]]), float(mags[fault[0]])
        run_chain(n, dt, np.radians(np.array(amp_deg, dtype=float)), w, math.radians(psi0_deg), suite, sstate,
                  np.random.default_rng(seed), chain, work, imu_raw, cell_raw, fault_step, fmod, fmode, fmag,
                  est_out, truth_out, q_out, health)
        return ChainResult(est_out, truth_out, q_out, health, dt, settle_s)

    return run
