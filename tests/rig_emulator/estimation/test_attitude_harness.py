"""The attitude chain end to end: calibration -> ensemble -> complementary filter on a closed harness.

Figures (seed 11/12 modules and calibration, seed 5 noise) are printed with ``-s``.
"""

import math

import numpy as np
import pytest

from rig_emulator.physics.rotation import quat_from_euler


def test_integrated_quaternion_follows_the_euler_trajectory(run_attitude):
    r = run_attitude(duration=10.0)
    q = np.zeros(4)
    for k in range(0, len(r.truth), 997):
        quat_from_euler(*r.truth[k, :3], q)
        assert min(np.abs(q - r.q[k]).max(), np.abs(q + r.q[k]).max()) < 1e-8


def test_static_and_hover_attitude_error_below_half_degree(run_attitude):
    static = run_attitude(amp_deg=(0.0, 0.0, 0.0))
    hover = run_attitude()
    print(f"\nstatic rms [deg] {static.rms_deg}, harmonic rms [deg] {hover.rms_deg}")
    assert static.rms_deg.max() < 0.5
    assert hover.rms_deg.max() < 0.5
    assert np.sqrt(np.mean(hover.rate_err ** 2)) < math.radians(0.2)


def test_calibration_is_what_makes_it_accurate(run_attitude):
    cal = run_attitude(amp_deg=(0.0, 0.0, 0.0))
    raw = run_attitude(amp_deg=(0.0, 0.0, 0.0), calibrated=False)
    tilt_cal = np.hypot(cal.err_deg[:, 0], cal.err_deg[:, 1]).mean()
    tilt_raw = np.hypot(raw.err_deg[:, 0], raw.err_deg[:, 1]).mean()
    print(f"\nstatic tilt error: calibrated {tilt_cal:.3f} deg, datasheet scaling only {tilt_raw:.3f} deg")
    assert tilt_raw > 10 * tilt_cal
    assert tilt_raw > 1.0


@pytest.mark.parametrize("fault", [("dead", 0.0), ("bias", 3000.0), ("stuck", 0.0), ("noise", 50.0)])
def test_robust_ensemble_survives_one_failed_module(run_attitude, fault):
    spec = (2, fault[0], fault[1], 10.0)
    robust = run_attitude(fault=spec)
    print(f"\n{fault}: robust rms [deg] {robust.rms_deg}")
    assert robust.rms_deg.max() < 1.0
    assert robust.health[-1] & (1 << 2)  # the failed module is flagged
    assert robust.health[: int(9.0 / 1e-3)].max() == 0  # nothing flagged before the fault


@pytest.mark.parametrize("fault", [("dead", 0.0), ("bias", 3000.0), ("stuck", 0.0)])
def test_plain_average_is_hurt_by_the_failure(run_attitude, fault):
    spec = (2, fault[0], fault[1], 10.0)
    robust = run_attitude(fault=spec)
    plain = run_attitude(fault=spec, mode="mean")
    print(f"\n{fault}: plain mean rms {plain.rms_total_deg:.3f} deg vs robust {robust.rms_total_deg:.3f} deg")
    assert plain.rms_total_deg > 3 * robust.rms_total_deg
    assert plain.rms_total_deg > 0.5
