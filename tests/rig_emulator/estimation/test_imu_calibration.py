"""LM calibration of the IMU modules (paper Sec. 4-1): recovery, application, file."""

import json

import numpy as np
import pytest

from rig_emulator.estimation.calibration_file import load_calibration, save_calibration
from rig_emulator.estimation.imu_calibration import apply_imu_calibration, calibration_orientations
from rig_emulator.sensors.imu_module import ACCEL, GYRO, MAG


def test_orientations_spread_over_the_sphere():
    e = calibration_orientations(24)
    assert np.allclose(e[0], 0.0)
    g_dirs = np.stack([-np.sin(e[:, 1]), -np.sin(e[:, 0]) * np.cos(e[:, 1]), -np.cos(e[:, 0]) * np.cos(e[:, 1])], 1)
    assert np.abs(g_dirs.mean(axis=0)).max() < 0.15  # balanced
    for axis in range(3):
        assert g_dirs[:, axis].max() > 0.8 and g_dirs[:, axis].min() < -0.8
    with pytest.raises(ValueError, match="n_orientations = 6"):
        calibration_orientations(6)


def test_calibration_recovers_bias_scale_and_non_orthogonality(chain_setup):
    imu, cal = chain_setup["imu"], chain_setup["cal"]
    k = imu.kernel
    bounds = {GYRO: np.radians(20.0), ACCEL: 0.05 * 9.80665, MAG: 0.1e-4}
    worst = {}
    for m in range(k.n_modules):
        for s in (GYRO, ACCEL, MAG):
            CA = cal.gain[m, s] / k.lsb[s] @ imu.error_matrix[m, s]
            sv = np.linalg.svd(CA, compute_uv=False)
            assert np.abs(sv - 1.0).max() < 1e-3, (m, s, sv)          # scale within 0.1 %
            assert np.abs(np.diag(CA) - 1.0).max() < 1e-3
            bias_err = cal.offset_counts[m, s] * k.lsb[s] - imu.offset_si[m, s]
            worst[s] = max(worst.get(s, 0.0), np.abs(bias_err).max() / bounds[s])
            assert np.abs(bias_err).max() < 0.02 * bounds[s], (m, s, bias_err)
        # the gyro's full matrix is aligned with B; the accelerometer's tilt is aligned
        assert np.abs(cal.gain[m, GYRO] / k.lsb[GYRO] @ imu.error_matrix[m, GYRO] - np.eye(3)).max() < 1e-3
        z = cal.gain[m, ACCEL] / k.lsb[ACCEL] @ imu.error_matrix[m, ACCEL] @ np.array([0.0, 0.0, 1.0])
        assert np.abs(z - [0.0, 0.0, 1.0]).max() < 1e-3
    print(f"\nworst bias error / datasheet bound: {worst}")


def test_apply_matches_the_definition(chain_setup):
    cal = chain_setup["cal"]
    rng = np.random.default_rng(0)
    raw = np.round(rng.normal(0, 3000, (5, 9)))
    out = np.zeros((5, 3, 3))
    apply_imu_calibration(raw, cal.arrays(), out)
    for m in range(5):
        for s in range(3):
            assert np.allclose(out[m, s], cal.gain[m, s] @ (raw[m, 3 * s:3 * s + 3] - cal.offset_counts[m, s]))


def test_file_round_trip_and_corrupt_file(chain_setup, tmp_path):
    cal = chain_setup["cal"]
    path = save_calibration(tmp_path / "run" / "imu_calibration.json", cal)
    back = load_calibration(path)
    assert np.array_equal(back.gain, cal.gain) and np.array_equal(back.offset_counts, cal.offset_counts)
    assert back.procedure["n_orientations"] == cal.procedure["n_orientations"]
    assert [p.name for p in path.parent.iterdir()] == ["imu_calibration.json"]  # no temp left
    path.write_text(path.read_text()[:200])
    with pytest.raises(ValueError, match="imu_calibration.json: calibration file is corrupt"):
        load_calibration(path)
    doc = json.loads(json.dumps({"format_version": 1, "kind": "imu", "gain": [[1.0]], "offset_counts": [],
                                 "residual_rms": []}))
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="imu_calibration.json: calibration file is corrupt"):
        load_calibration(path)
