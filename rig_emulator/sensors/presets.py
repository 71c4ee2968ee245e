"""Sensor and estimation parameter files: load, override, validate.

The datasheet defaults live in ``rig_emulator/presets/sensors/<name>.toml``. Every figure
can be overridden by a nested dict (``{"gyro": {"full_scale_dps": 500}}``). Each leaf is
checked against :data:`SPECS`; an error names the file, the dotted key, the value and
the allowed range, e.g. ``ValueError("mpu6050: gyro.full_scale_dps = 300: must be one
of 250, 500, 1000, 2000")``.
"""

from __future__ import annotations

import copy
import functools
import json
import math
import tomllib
from importlib import resources
from typing import Any, Mapping

from rig_emulator.build_cache import BuildCache


class _Num:
    def __init__(self, lo: float, hi: float, integer: bool = False, lo_open: bool = False):
        self.lo, self.hi, self.integer, self.lo_open = lo, hi, integer, lo_open

    def check(self, key: str, value: Any) -> Any:
        kind = "an integer" if self.integer else "a number"
        lo = "(" if self.lo_open else "["
        rng = f"{kind} in {lo}{self.lo:g}, {self.hi:g}]"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{key} = {value!r}: must be {rng}")
        if self.integer and isinstance(value, float) and not value.is_integer():
            raise ValueError(f"{key} = {value!r}: must be {rng}")
        below = value <= self.lo if self.lo_open else value < self.lo
        if not math.isfinite(value) or below or value > self.hi:
            raise ValueError(f"{key} = {value!r}: must be {rng}")
        return int(value) if self.integer else float(value)


class _Choice:
    def __init__(self, *choices):
        self.choices = choices

    def check(self, key: str, value: Any) -> Any:
        for c in self.choices:
            if isinstance(c, str) == isinstance(value, str) and not isinstance(value, bool) and value == c:
                return c
        allowed = ", ".join(str(c) for c in self.choices)
        raise ValueError(f"{key} = {value!r}: must be one of {allowed}")


class _Table:
    """A list of fixed-length number rows (e.g. module positions)."""

    def __init__(self, width: int, lo: float, hi: float, min_rows: int = 1):
        self.width, self.lo, self.hi, self.min_rows = width, lo, hi, min_rows

    def check(self, key: str, value: Any) -> Any:
        what = f"a list of >= {self.min_rows} rows of {self.width} numbers in [{self.lo:g}, {self.hi:g}]"
        if not isinstance(value, (list, tuple)) or len(value) < self.min_rows:
            raise ValueError(f"{key} = {value!r}: must be {what}")
        rows = []
        for row in value:
            if not isinstance(row, (list, tuple)) or len(row) != self.width:
                raise ValueError(f"{key} = {value!r}: must be {what}")
            rows.append([_Num(self.lo, self.hi).check(key, v) for v in row])
        return rows


class _NumList:
    """A non-empty list of numbers in a range (e.g. calibration masses)."""

    def __init__(self, lo: float, hi: float):
        self.lo, self.hi = lo, hi

    def check(self, key: str, value: Any) -> Any:
        if not isinstance(value, (list, tuple)) or not value:
            raise ValueError(f"{key} = {value!r}: must be a non-empty list of numbers in [{self.lo:g}, {self.hi:g}]")
        return [_Num(self.lo, self.hi).check(key, v) for v in value]


def _pos(hi, integer=False):
    return _Num(0.0, hi, integer=integer, lo_open=True)


def _nonneg(hi, integer=False):
    return _Num(0.0, hi, integer=integer)


SPECS: dict[str, dict[str, Any]] = {
    "mpu6050": {
        "gyro.full_scale_dps": _Choice(250, 500, 1000, 2000),
        "gyro.adc_bits": _Choice(16),
        "gyro.noise_dps_per_rthz": _nonneg(1.0),
        "gyro.noise_bandwidth_hz": _pos(8000.0),
        "gyro.zero_rate_offset_dps": _nonneg(100.0),
        "gyro.scale_tolerance": _nonneg(0.2),
        "gyro.cross_axis": _nonneg(0.2),
        "gyro.bias_walk_dps_per_rts": _nonneg(1.0),
        "accel.full_scale_g": _Choice(2, 4, 8, 16),
        "accel.adc_bits": _Choice(16),
        "accel.noise_ug_per_rthz": _nonneg(10000.0),
        "accel.noise_bandwidth_hz": _pos(4000.0),
        "accel.zero_g_offset_xy_mg": _nonneg(500.0),
        "accel.zero_g_offset_z_mg": _nonneg(500.0),
        "accel.scale_tolerance": _nonneg(0.2),
        "accel.cross_axis": _nonneg(0.2),
        "accel.bias_walk_ug_per_rts": _nonneg(10000.0),
    },
    "hmc5883l": {
        "mag.full_scale_gauss": _Choice(0.88, 1.3, 1.9, 2.5, 4.0, 4.7, 5.6, 8.1),
        "mag.adc_bits": _Choice(12),
        "mag.noise_mgauss": _nonneg(100.0),
        "mag.scale_tolerance": _nonneg(0.2),
        "mag.cross_axis": _nonneg(0.2),
        "mag.hard_iron_gauss": _nonneg(1.0),
        "mag.soft_iron": _nonneg(0.3),
        "mag.bias_walk_mgauss_per_rts": _nonneg(100.0),
    },
    "zemic_l6d": {
        "load_cell.n_cells": _Num(1, 16, integer=True),
        "load_cell.decimation": _Num(1, 1000, integer=True),
        "load_cell.capacity_kgf": _pos(100.0),
        "load_cell.adc_bits": _Choice(10),
        "load_cell.step_grf": _pos(100.0),
        "load_cell.step_tolerance": _nonneg(0.5),
        "load_cell.zero_reading_counts": _Num(0.0, 1023.0),
        "load_cell.zero_reading_spread_counts": _nonneg(100.0),
        "load_cell.noise_floor_grf": _nonneg(1000.0),
        "load_cell.vibration_grf_at_hover": _nonneg(1000.0),
        "load_cell.rotor_speed_hover_rad_s": _pos(1e4),
        "load_cell.spike_probability": _Num(0.0, 1.0),
    },
    "imu_array": {
        "array.n_modules": _Num(1, 16, integer=True),
        "array.positions_m": _Table(3, -1.0, 1.0),
        "array.misalignment_deg_rms": _nonneg(10.0),
        "sampling.gyro_accel_decimation": _Num(1, 1000, integer=True),
        "sampling.mag_decimation": _Num(1, 1000, integer=True),
        "site.gravity_m_s2": _pos(100.0),
        "site.earth_field_uT": _pos(120.0),
        "site.inclination_deg": _Num(-90.0, 90.0),
        "site.declination_deg": _Num(-180.0, 180.0),
    },
    "estimation": {
        "imu_calibration.n_orientations": _Num(12, 1000, integer=True),
        "imu_calibration.hold_s": _pos(600.0),
        "imu_calibration.rotation_rate_dps": _pos(200.0),
        "imu_calibration.rotation_s": _pos(60.0),
        "load_cell_calibration.masses_g": _NumList(1.0, 2500.0),
        "load_cell_calibration.n_samples": _Num(1, 10**6, integer=True),
        "ensemble.mode": _Choice("mean", "median", "robust_mean"),
        "ensemble.gyro_reject_dps": _pos(1000.0),
        "ensemble.accel_reject_m_s2": _pos(200.0),
        "ensemble.mag_reject_uT": _pos(1000.0),
        "complementary.tau_roll_pitch_s": _pos(1000.0),
        "complementary.tau_yaw_s": _pos(1000.0),
        "complementary.accel_lowpass_hz": _pos(1000.0),
        "complementary.accel_gate_m_s2": _pos(100.0),
        "complementary.declination_deg": _Num(-180.0, 180.0),
        "load_cell_filter.mode": _Choice("none", "iir", "kalman"),
        "load_cell_filter.jump_threshold_grf": _pos(1e5),
        "load_cell_filter.max_thrust_grf": _pos(1e5),
        "load_cell_filter.min_thrust_grf": _Num(-1e5, 0.0),
        "load_cell_filter.reaccept_after": _Num(0, 10**6, integer=True),
        "load_cell_filter.iir_cutoff_hz": _pos(1000.0),
        "load_cell_filter.kalman_measurement_sigma_grf": _pos(1e4),
        "load_cell_filter.kalman_accel_noise_grf_per_s2_rthz": _pos(1e7),
    },
}


def _flatten(tree: Mapping, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in tree.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(_flatten(value, dotted + "."))
        else:
            out[dotted] = value
    return out


def _set(tree: dict, dotted: str, value: Any) -> None:
    parts = dotted.split(".")
    for p in parts[:-1]:
        tree = tree.setdefault(p, {})
    tree[parts[-1]] = value


def load_sensor_preset(name: str, overrides: Mapping | None = None) -> dict:
    """Read ``presets/sensors/<name>.toml``, apply nested ``overrides``, validate every leaf.

    Returns the nested dict with numbers converted (ints stay ints, floats are floats).
    Raises ``ValueError`` naming ``<name>: <dotted.key> = <value>`` and the allowed range.
    The result of a (name, overrides) pair is computed once per process (presets are package
    data); every call returns its own copy.
    """
    key = _overrides_key(overrides)
    return _RESULTS.get_or_build(None if key is None else (name, key), lambda: _load_sensor_preset(name, overrides))


_RESULTS = BuildCache(256)  # (name, canonical overrides) -> validated tree


def _overrides_key(overrides: Mapping | None) -> str | None:
    """A canonical text of ``overrides`` (None when JSON cannot show it: such input is
    validated uncached)."""
    if not overrides:
        return ""
    try:
        return json.dumps(overrides, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError):
        return None


def _preset_path(name: str):
    return resources.files("rig_emulator") / "presets" / "sensors" / f"{name}.toml"


@functools.lru_cache(maxsize=None)
def _preset_file(name: str) -> dict:
    path = _preset_path(name)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML ({exc})") from exc


def _load_sensor_preset(name: str, overrides: Mapping | None) -> dict:
    if name not in SPECS:
        raise ValueError(f"unknown sensor preset {name!r}: choose one of {', '.join(sorted(SPECS))}")
    path = _preset_path(name)
    tree = copy.deepcopy(_preset_file(name))
    if overrides:
        for key, value in _flatten(overrides).items():
            if key not in SPECS[name]:
                raise ValueError(f"{name}: unknown key {key!r}; known keys: {', '.join(SPECS[name])}")
            _set(tree, key, value)
    flat = _flatten(tree)
    for key in flat:
        if key not in SPECS[name]:
            raise ValueError(f"{name}: unknown key {key!r} in {path}")
    out: dict = {}
    for key, spec in SPECS[name].items():
        if key not in flat:
            raise ValueError(f"{name}: missing key {key!r}")
        _set(out, key, spec.check(f"{name}: {key}", flat[key]))
    return out
