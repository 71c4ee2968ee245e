"""The sensor readings the link publishes, taken from a :class:`RigSnapshot`.

:func:`sensor_readings` is the single function every sensor stream (SCALED_IMU*,
HIGHRES_IMU, HILMS_IMU_MODULE, HILMS_LOAD_CELLS and its NAMED_VALUE_FLOAT mirror, the
SYS_STATUS sensor health bits) reads. Until the snapshot carries the simulated sensors'
fields it computes the **ideal** readings from the true state - error-free and noiseless,
at the datasheet scaling of the rig's devices:

* gyro = ``omega_B`` (FRD, rad/s);
* accelerometer = the specific force at the joint, ``R_WB^T [0, 0, g]`` in FRD (the
  lever-arm terms of modules off the joint need ``omega_dot``, which the snapshot lacks);
* magnetometer = ``R_WB^T m_W`` with the site's earth field (``imu_array.toml``);
* raw IMU counts = reading / LSB of the MPU6050 / HMC5883L presets, rounded and saturated;
* load cells: thrust = ``snapshot.thrusts``; force in gram-force; raw counts =
  ``b + F_grf / C`` with the nominal ``b`` and ``C`` of ``zemic_l6d.toml``;
* every device healthy.

When the snapshot gains ``imu_raw``, ``load_cells_raw``, ``load_cells_grf``,
``load_cells_filtered_n`` and the per-sensor health, only this function changes.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from rig_emulator.sensors.imu_module import earth_field_enu, load_imu_config, sensor_scaling
from rig_emulator.sensors.load_cell import GRF_N, load_load_cell_config


@dataclass(frozen=True)
class SensorModel:
    """Nominal device scaling, read once from the sensor presets."""

    n_modules: int
    lsb: np.ndarray  # (3,) SI per count: gyro, accel, mag
    count_min: np.ndarray
    count_max: np.ndarray
    earth_field_w: np.ndarray  # T, ENU
    n_cells: int
    cell_zero_counts: float
    cell_grf_per_count: float
    cell_count_max: float

    @functools.cached_property
    def raw_scaling(self) -> tuple:
        """(LSB, lowest count, highest count) of each of the 9 raw IMU channels: gyro x3, accel x3, mag x3."""
        return np.repeat(self.lsb, 3), np.repeat(self.count_min, 3), np.repeat(self.count_max, 3)


def load_sensor_model() -> SensorModel:
    imu = load_imu_config()
    scale = sensor_scaling(imu)
    cells = load_load_cell_config()["load_cell"]
    return SensorModel(
        n_modules=int(imu["imu_array"]["array"]["n_modules"]),
        lsb=scale["lsb"], count_min=scale["count_min"], count_max=scale["count_max"],
        earth_field_w=earth_field_enu(imu["imu_array"]["site"]),
        n_cells=int(cells["n_cells"]),
        cell_zero_counts=float(cells["zero_reading_counts"]),
        cell_grf_per_count=float(cells["step_grf"]),
        cell_count_max=float(2 ** cells["adc_bits"] - 1),
    )


@dataclass(frozen=True)
class SensorReadings:
    """Every published sensor value at one instant (SI unless the name says counts/grf)."""

    gyro: np.ndarray  # (n_modules, 3) rad/s, FRD
    accel: np.ndarray  # (n_modules, 3) m/s^2, FRD
    mag: np.ndarray  # (n_modules, 3) T, FRD
    imu_raw_counts: np.ndarray  # (n_modules, 9): gyro, accel, mag counts
    imu_faults: tuple  # (n_modules,) injected HILMS_FAULT codes, 0 = none
    fused_gyro: np.ndarray  # (3,)
    fused_accel: np.ndarray
    fused_mag: np.ndarray
    load_raw_counts: np.ndarray  # (n_cells,)
    load_force_grf: np.ndarray
    load_thrust_n: np.ndarray  # filtered thrust the rig uses
    load_faults: tuple  # (n_cells,) HILMS_FAULT codes, 0 = healthy
    ideal: bool  # True while these come from the true state
    imu_rejected: tuple = ()  # (n_modules,) True where the ensemble rejects the module
    load_rejected: tuple = ()  # (n_cells,) True where a guard rejected the last reading

    @property
    def imu_healthy(self) -> tuple:
        rejected = self.imu_rejected or (False,) * len(self.imu_faults)
        return tuple(f == 0 and not r for f, r in zip(self.imu_faults, rejected))

    @property
    def load_healthy(self) -> tuple:
        rejected = self.load_rejected or (False,) * len(self.load_faults)
        return tuple(f == 0 and not r for f, r in zip(self.load_faults, rejected))


def sensor_readings(snap, model: SensorModel, gravity: float) -> SensorReadings:
    """The readings of :class:`SensorReadings` for ``snap``: the simulated sensors' when the
    snapshot carries them, else the ideal ones of the module doc."""
    if snap.sensors is not None:
        return _simulated(snap.sensors)
    r_wb = snap.rotation
    gyro1 = np.asarray(snap.body_rates, dtype=float)
    accel1 = r_wb.T @ np.array([0.0, 0.0, gravity])
    mag1 = r_wb.T @ model.earth_field_w
    n = model.n_modules
    lsb, lo, hi = model.raw_scaling
    # every module reads the same (ideal): one row computed, then repeated (a .tlog export calls this per row)
    # (np.minimum / np.maximum: np.clip's own overhead was most of a row's time)
    row = np.concatenate((gyro1, accel1, mag1))
    block = np.repeat(np.concatenate((row, np.minimum(np.maximum(np.round(row / lsb), lo), hi)))[None, :], n, axis=0)
    gyro, accel, mag, raw = block[:, 0:3], block[:, 3:6], block[:, 6:9], block[:, 9:18]
    thrust = np.asarray(snap.thrusts, dtype=float)
    grf = thrust / GRF_N
    cells = np.minimum(np.maximum(np.round(model.cell_zero_counts + grf / model.cell_grf_per_count), 0.0),
                       model.cell_count_max)
    return SensorReadings(
        gyro=gyro, accel=accel, mag=mag, imu_raw_counts=raw, imu_faults=(0,) * n,
        fused_gyro=gyro1, fused_accel=accel1, fused_mag=mag1,
        load_raw_counts=cells, load_force_grf=grf, load_thrust_n=thrust,
        load_faults=(0,) * model.n_cells, ideal=True,
    )


def _fault_codes(modes) -> tuple:
    """rig_emulator.sensors.faults codes are HILMS_FAULT codes (NONE STUCK DEAD BIAS NOISE SPIKE)."""
    return tuple(map(int, modes))


@functools.lru_cache(maxsize=256)
def _mask_bits(mask: int, n: int) -> tuple:
    """(bit 0 set, bit 1 set, ...) of ``mask`` for ``n`` devices (read per served chunk: cached)."""
    return tuple(bool(mask & (1 << i)) for i in range(n))


def _simulated(sensors) -> SensorReadings:
    """The simulated sensors' readings (raw counts, calibrated SI, the ensemble, load cells)."""
    si = sensors.imu_si
    fused = sensors.fused
    imu_faults = _fault_codes(sensors.imu_fault_modes)
    cell_faults = _fault_codes(sensors.cell_fault_modes)
    return SensorReadings(
        gyro=si[:, 0, :], accel=si[:, 1, :], mag=si[:, 2, :], imu_raw_counts=sensors.imu_raw,
        imu_faults=imu_faults,
        fused_gyro=fused[0], fused_accel=fused[1], fused_mag=fused[2],
        load_raw_counts=sensors.cell_raw, load_force_grf=sensors.cell_grf, load_thrust_n=sensors.cell_thrust_n,
        load_faults=cell_faults, ideal=False,
        imu_rejected=_mask_bits(int(sensors.imu_rejected_mask), len(imu_faults)),
        load_rejected=_mask_bits(int(sensors.cell_rejected_mask), len(cell_faults)),
    )
