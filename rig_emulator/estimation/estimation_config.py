"""The estimation chain's parameters: ``presets/sensors/estimation.toml`` plus overrides."""

from __future__ import annotations

from rig_emulator.sensors.presets import load_sensor_preset


def load_estimation_config(overrides: dict | None = None) -> dict:
    """Defaults of calibration, ensemble, complementary filter and load-cell filter.

    Example: ``load_estimation_config({"load_cell_filter": {"mode": "kalman"}})``.
    """
    return load_sensor_preset("estimation", overrides)
