"""The motor currents' magnetic field (physics/hardware.py ``motor_field_step``) reaches the
rig's heading through all five magnetometers alike: the ensemble of Sec. 4-1 cannot average it away."""

import math

import numpy as np
import pytest

from rig_emulator.api import simulate

# presets/sensors/imu_array.toml: 47 uT dipping 52 deg, so 28.9 uT horizontal
HORIZONTAL_FIELD_UT = 47.0 * math.cos(math.radians(52.0))


def _heading_error_rms(ripple_uT: float) -> float:
    # the ideal plant hovering, the heading taken from the magnetometers at each sample (tau <= 10 ms)
    r = simulate("hover", strategy="flc", duration=6.0, seed=2, airframe="hilms-ideal",
                 **{"estimation.tau_yaw": 0.01, "motor_field.ripple_uT": ripple_uT})
    keep = r.series["t"] > 2.0
    err = np.angle(np.exp(1j * (r.series["euler"][keep, 2] - r.series["euler_true"][keep, 2])))
    return float(np.std(err))


def test_the_ripple_field_becomes_heading_noise_of_its_size_and_the_ensemble_keeps_it():
    quiet = _heading_error_rms(0.0)
    noisy = _heading_error_rms(0.3)
    # near psi = 0 the leads along body x (motors 1 and 3) put their field across the horizontal
    # component: sqrt(2) x 0.3 uT over 28.9 uT, 0.0147 rad a sample
    expected = math.sqrt(2.0) * 0.3 / HORIZONTAL_FIELD_UT
    assert quiet < 0.3 * expected  # the modules' own 2 mG noise, averaged by the ensemble
    assert math.sqrt(noisy ** 2 - quiet ** 2) == pytest.approx(expected, rel=0.1)
