"""Our complementary filter against ``ahrs.filters.Complementary``.

Both filters get the same 100,000 IMU samples (1 kHz, 100 s) of a smooth dynamic attitude
trajectory (roll / pitch / yaw sinusoids of 25 / 20 / 40 deg, 0.8 rad/s, heading offset
20 deg), with ensemble-level noise of five calibrated modules and the magnetometer at
100 Hz (held between samples), exactly as in
``tests/rig_emulator/estimation/test_complementary.py``, which also documents the frame
conversions: ahrs gets FLU axes (``diag(1,-1,-1)`` of our FRD), the magnetometer in uT,
``gain = 1 - dt / tau_roll_pitch_s``, and its yaw is shifted by
``alpha = 90 deg - declination``.

Figures: time per sample of ours in a compiled loop (a ``numba.njit`` loop in this
module calling ``complementary_step``; compiled in each process, compile time reported
separately), of ours called from Python sample by sample, and of ahrs (its batch
constructor over all samples); RMS attitude error vs truth per angle after the first
:data:`SETTLE_S` seconds, for both.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .harness import BenchmarkUnavailable, Metric, ProbeStats, benchmark, paired_ratio_metric, probe

OURS_PROBE = "cf-ours"
AHRS_PROBE = "cf-ahrs"

DT_S = 1e-3
MAG_DECIMATION = 10
SETTLE_S = 5.0
AMPLITUDE_DEG = (25.0, 20.0, 40.0)
OMEGA_RAD_S = 0.8
PSI0_DEG = 20.0
GRAVITY = 9.81
ANGLES = ("roll", "pitch", "yaw")


# ----------------------------------------------------------------------------------------
# Pure helpers (numpy only; unit-tested)
# ----------------------------------------------------------------------------------------


def wrap_pi(a):
    """Wrap angles to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def rwb_many(phi, theta, psi) -> np.ndarray:
    """``R_WB`` of Eq. 2 for arrays of angles, shape ``(n, 3, 3)`` (same formulas as
    ``rig_emulator.physics.rotation.rwb_from_euler``)."""
    cph, sph = np.cos(phi), np.sin(phi)
    cth, sth = np.cos(theta), np.sin(theta)
    cps, sps = np.cos(psi), np.sin(psi)
    return np.stack([
        np.stack([cps * cth, sps * cph - cps * sth * sph, -sps * sph - cps * sth * cph], -1),
        np.stack([sps * cth, -cps * cph - sps * sth * sph, cps * sph - sps * sth * cph], -1),
        np.stack([-sth, -cth * sph, -cth * cph], -1),
    ], -2)


def trajectory(n: int, dt: float, amp, w: float, psi0: float, m_w, g: float = GRAVITY):
    """Truth angles ``(n, 3)``, body rates (FRD) ``(n, 3)``, specific force and field in body
    axes, ``(n, 3)`` each; the trajectory of ``test_complementary.py``."""
    t = np.arange(n) * dt
    phi = amp[0] * np.sin(w * t)
    theta = amp[1] * np.sin(w * t + 1.0)
    psi = psi0 + amp[2] * np.sin(0.5 * w * t + 2.0)
    dphi = amp[0] * w * np.cos(w * t)
    dtheta = amp[1] * w * np.cos(w * t + 1.0)
    dpsi = amp[2] * 0.5 * w * np.cos(0.5 * w * t + 2.0)
    p = dphi - np.sin(theta) * dpsi
    q = np.cos(phi) * dtheta + np.sin(phi) * np.cos(theta) * dpsi
    r = -np.sin(phi) * dtheta + np.cos(phi) * np.cos(theta) * dpsi
    omega = np.stack([p, -q, -r], 1)
    R = rwb_many(phi, theta, psi)
    f = g * R[:, 2, :]  # R^T [0, 0, g]
    m = np.einsum("nji,j->ni", R, np.asarray(m_w, dtype=np.float64))
    return np.stack([phi, theta, psi], 1), omega, f, m


def hold_every(x: np.ndarray, every: int) -> np.ndarray:
    """Sample-and-hold: row ``k`` becomes row ``every * (k // every)``."""
    idx = (np.arange(len(x)) // every) * every
    return x[idx]


def rms_error_deg(est: np.ndarray, truth: np.ndarray, skip: int) -> np.ndarray:
    """RMS of the wrapped angle error per column after ``skip`` rows, in degrees."""
    return np.degrees(np.sqrt(np.mean(wrap_pi(est[skip:] - truth[skip:]) ** 2, axis=0)))


def _inputs(n: int, seed: int):
    from rig_emulator.sensors.imu_module import earth_field_enu, load_imu_config

    site = load_imu_config()["imu_array"]["site"]
    m_w = earth_field_enu(site)
    alpha = math.radians(90.0 - site["declination_deg"])
    truth, omega, f, m = trajectory(n, DT_S, np.radians(AMPLITUDE_DEG), OMEGA_RAD_S,
                                    math.radians(PSI0_DEG), m_w)
    rng = np.random.default_rng(seed)
    gyro = omega + rng.normal(0, math.radians(0.08) / math.sqrt(5), (n, 3))
    acc = f + rng.normal(0, 0.0063 * GRAVITY / math.sqrt(5), (n, 3))
    mag = hold_every(m + rng.normal(0, 2e-7 / math.sqrt(5), (n, 3)), MAG_DECIMATION)
    return truth, gyro, acc, mag, alpha


def _tau():
    from rig_emulator.estimation.estimation_config import load_estimation_config

    est = load_estimation_config()
    return est, est["complementary"]["tau_roll_pitch_s"]


def _errors(prefix: str, est: np.ndarray, truth: np.ndarray) -> dict:
    e = rms_error_deg(est, truth, int(round(SETTLE_S / DT_S)))
    return {f"{prefix}rms_{a}_deg": float(v) for a, v in zip(ANGLES, e)}


# ----------------------------------------------------------------------------------------
# Probes
# ----------------------------------------------------------------------------------------

_LOOP = None


def _compiled_loop():
    """``numba.njit`` loop over samples calling ``complementary_step`` (built on first use)."""
    global _LOOP
    if _LOOP is None:
        from numba import njit

        from rig_emulator.estimation.complementary import complementary_step

        @njit
        def run(gyro, acc, mag, mag_every, p, state, est):
            out = np.zeros(6)
            for k in range(gyro.shape[0]):
                complementary_step(gyro[k], acc[k], mag[k], k % mag_every == 0, p, state, out)
                est[k, 0] = out[0]
                est[k, 1] = out[1]
                est[k, 2] = out[2]

        _LOOP = run
    return _LOOP


@probe(OURS_PROBE, params={"n": 100_000, "n_python": 20_000, "seed": 3},
       quick={"n_python": 2_000},
       description="our complementary filter over 100k samples: compiled loop and from Python")
def cf_ours(n: int, n_python: int, seed: int) -> dict:
    """Our filter: compiled loop over all samples, Python per-sample calls, RMS error."""
    from rig_emulator.estimation.complementary import (
        complementary_params, complementary_state, complementary_step)

    truth, gyro, acc, mag, _ = _inputs(n, seed)
    est_cfg, _tau_s = _tau()
    p = complementary_params(est_cfg, DT_S, MAG_DECIMATION * DT_S, GRAVITY)
    loop = _compiled_loop()
    est = np.zeros((n, 3))
    t0 = time.perf_counter()
    loop(gyro[:2], acc[:2], mag[:2], MAG_DECIMATION, p, complementary_state(), est[:2])
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    loop(gyro, acc, mag, MAG_DECIMATION, p, complementary_state(), est)
    wall = time.perf_counter() - t0
    # from Python, sample by sample (as a Python caller would), on the first n_python samples
    state = complementary_state()
    out = np.zeros(6)
    complementary_step(gyro[0], acc[0], mag[0], True, p, complementary_state(), out)  # dispatch warm-up
    t0 = time.perf_counter()
    for k in range(n_python):
        complementary_step(gyro[k], acc[k], mag[k], k % MAG_DECIMATION == 0, p, state, out)
    py_wall = time.perf_counter() - t0
    return {"us_per_sample": wall / n * 1e6, "us_per_sample_python": py_wall / n_python * 1e6,
            "compile_s": compile_s, "n": n, **_errors("", est, truth)}


@probe(AHRS_PROBE, params={"n": 100_000, "seed": 3},
       description="ahrs.filters.Complementary over the same 100k samples")
def cf_ahrs(n: int, seed: int) -> dict:
    """ahrs' complementary filter (batch constructor) on the same samples, RMS error."""
    try:
        import ahrs
        from ahrs.filters import Complementary
    except ImportError as exc:
        raise BenchmarkUnavailable(
            f"ahrs is not importable ({exc}); install it (`pip install -e '.[bench]'`)"
        ) from None
    truth, gyro, acc, mag, alpha = _inputs(n, seed)
    _est, tau = _tau()
    flu = np.array([1.0, -1.0, -1.0])
    g, a, m = gyro * flu, acc * flu, mag * flu * 1e6
    t0 = time.perf_counter()
    ref = Complementary(gyr=g, acc=a, mag=m, Dt=DT_S, gain=1.0 - DT_S / tau)
    wall = time.perf_counter() - t0
    theirs = np.array(ref.W, dtype=np.float64).copy()
    theirs[:, 2] += alpha
    return {"us_per_sample": wall / n * 1e6, "n": n, "ahrs_version": str(ahrs.__version__),
            **_errors("", theirs, truth)}


@benchmark("cf-vs-ahrs", probes=(OURS_PROBE, AHRS_PROBE))
def cf_vs_ahrs(stats: dict[str, ProbeStats]) -> list[Metric]:
    """Our complementary filter vs ahrs' on the same 100k samples."""
    ours, theirs = stats[OURS_PROBE], stats[AHRS_PROBE]
    out = [
        ours.metric("us_per_sample", "ours per sample, compiled loop", "us"),
        ours.metric("us_per_sample_python", "ours per sample, called from Python", "us"),
        theirs.metric("us_per_sample", "ahrs per sample (batch constructor)", "us"),
        paired_ratio_metric(theirs, "us_per_sample", ours, "us_per_sample",
                            "speed-up over ahrs, compiled loop"),
        paired_ratio_metric(theirs, "us_per_sample", ours, "us_per_sample_python",
                            "speed-up over ahrs, from Python"),
        ours.metric("compile_s", "ours: compile of the benchmark loop", "s"),
    ]
    note = f"RMS over samples after the first {SETTLE_S:g} s, vs the true Z-Y-X angles"
    for a in ANGLES:
        out.append(ours.metric(f"rms_{a}_deg", f"RMS {a} error, ours", "deg", note=note))
        out.append(theirs.metric(f"rms_{a}_deg", f"RMS {a} error, ahrs", "deg", note=note))
    return out
