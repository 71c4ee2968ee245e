"""Sensor parameter files: defaults, nested overrides, errors that name key and range."""

import pytest

from rig_emulator.sensors.imu_module import load_imu_config
from rig_emulator.sensors.presets import SPECS, load_sensor_preset


@pytest.mark.parametrize("name", sorted(SPECS))
def test_every_preset_loads_and_is_complete(name):
    cfg = load_sensor_preset(name)
    assert cfg  # every key of SPECS was present and valid


def test_override_changes_one_figure():
    cfg = load_sensor_preset("mpu6050", {"gyro": {"full_scale_dps": 500}})
    assert cfg["gyro"]["full_scale_dps"] == 500
    assert cfg["accel"]["full_scale_g"] == 2


@pytest.mark.parametrize(
    "name, overrides, message",
    [
        ("mpu6050", {"gyro": {"full_scale_dps": 300}}, "gyro.full_scale_dps = 300: must be one of 250, 500, 1000, 2000"),
        ("hmc5883l", {"mag": {"noise_mgauss": -1.0}}, "mag.noise_mgauss = -1.0: must be a number in [0, 100]"),
        ("zemic_l6d", {"load_cell": {"decimation": 2.5}}, "load_cell.decimation = 2.5: must be an integer"),
        ("estimation", {"ensemble": {"mode": "vote"}}, "ensemble.mode = 'vote': must be one of mean, median, robust_mean"),
        ("estimation", {"imu_calibration": {"n_orientations": 6}}, "imu_calibration.n_orientations = 6"),
        ("imu_array", {"array": {"positions_m": [[0.0, 0.0]]}}, "array.positions_m"),
        ("mpu6050", {"gyro": {"fullscale": 1}}, "unknown key 'gyro.fullscale'"),
    ],
)
def test_bad_values_are_named(name, overrides, message):
    with pytest.raises(ValueError, match=None) as exc:
        load_sensor_preset(name, overrides)
    assert message in str(exc.value)
    assert str(exc.value).startswith(name) or "unknown" in str(exc.value)


def test_module_count_must_match_positions():
    with pytest.raises(ValueError, match="array.positions_m has 5 rows: must have array.n_modules = 4"):
        load_imu_config({"imu_array": {"array": {"n_modules": 4}}})
