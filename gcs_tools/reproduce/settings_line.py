"""The line of a reproduction report that says which emulator settings its runs used."""

from __future__ import annotations


def settings_line(airframe: str = "hilms") -> str:
    from rig_emulator.config.loader import load_config

    cfg = load_config(airframe)
    return (f"Emulator settings (the presets, unchanged) of the plant `{airframe}` the detailed sections below "
            f"show: physics {cfg['sim.physics_rate_hz']:g} Hz, control "
            f"{cfg['sim.control_rate_hz']:g} Hz, SMC gains of Eq. 41 read as `smc.gain_reading = "
            f"\"{cfg['smc.gain_reading']}\"`, `smc.lambda_reading = \"{cfg['smc.lambda_reading']}\"` with "
            f"`smc.switching = \"{cfg['smc.switching']}\"`, FLC of Tables 1, 3 and 5, controllers fed by the simulated sensors "
            f"(`sensors.feedback = \"{cfg['sensors.feedback']}\"`), load-cell filter `{cfg['estimation.load_cell_filter']}`"
            " unless an experiment says otherwise.")
