"""Parameter files: presets load, every bad value is named with its allowed range."""

import pytest

from rig_emulator.config.loader import ConfigError, available, load_config, parse_override
from rig_emulator.config.schema import SCHEMA


def test_defaults_cover_the_whole_schema():
    cfg = load_config()
    assert set(cfg) == set(SCHEMA)
    assert cfg["airframe.mass"] == 2.23
    assert cfg["smc.k"] == [1.47, 1.47, 1.42]


@pytest.mark.parametrize(
    "name, mass, ixx, izz, arm",
    [("hilms", 2.23, 6.2e-2, 1.16e-1, 0.28), ("hilms-ideal", 2.23, 6.2e-2, 1.16e-1, 0.28), ("os4", 0.65, 7.5e-3, 1.3e-2, 0.23), ("draganflyer", 0.5, 4.85e-3, 8.81e-3, 0.2)],
)
def test_table_2_airframes(name, mass, ixx, izz, arm):
    cfg = load_config(airframe=name)
    assert (cfg["airframe.mass"], cfg["airframe.ixx"], cfg["airframe.izz"], cfg["airframe.arm_length"]) == (mass, ixx, izz, arm)


def test_every_scenario_preset_loads():
    for name in available("scenarios"):
        load_config(scenario=name)
    assert {"hover-shocks", "harmonic", "helix", "rectangle", "extra-mass"} <= set(available("scenarios"))


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("airframe.mass", -1.0, ["airframe.mass", "(0, 100]"]),
        ("control.strategy", "lqr", ["control.strategy", "smc-flc"]),
        ("guidance.omega", 0.0, ["guidance.omega", "(0"]),
        ("guidance.omega", -0.4, ["guidance.omega"]),
        ("smc.k", [1.0, 2.0], ["smc.k", "exactly 3"]),
        ("smc.lam", [1.0, -2.0, 1.0], ["smc.lam[1]"]),
        ("sim.control_rate_hz", 300.0, ["sim.control_rate_hz", "whole number"]),
        ("disturbance.shocks", [{"t": 1.0, "arm": 5, "torque": 1.0, "duration": 0.1}], ["disturbance.shocks[0].arm", "[1, 4]"]),
        ("sim.duration", float("nan"), ["sim.duration", "finite"]),
        ("sim.ground", 1, ["sim.ground", "true or false"]),
        ("joint.viscous", [0.1, -0.1, 0.0], ["joint.viscous[1]", "[0, 10]"]),
        ("joint.cog_offset", [0.0, 0.0, 0.5], ["joint.cog_offset[2]", "[-0.1, 0.1] m"]),
        ("motors.thrust_gain", [1.0, 1.0, 1.0], ["motors.thrust_gain", "exactly 4"]),
        ("motors.curve_exponent", 0.5, ["motors.curve_exponent", "[1, 3]"]),
        ("motors.command_steps", 2.5, ["motors.command_steps", "integer"]),
        ("control.actuation_delay", 0.5, ["control.actuation_delay", "[0, 0.1] s"]),
        ("smc.gain_reading", "newton", ["smc.gain_reading", "'thrust'"]),
        ("smc.lambda_reading", "rad", ["smc.lambda_reading", "'deg'"]),
        ("disturbance.torque_noise_corner_hz", 0.0, ["disturbance.torque_noise_corner_hz", "(0"]),
        ("vibration.blades", 0, ["vibration.blades", "[1, 8]"]),
        ("controller_model.inertia_scale", [1.0, 0.0, 1.0], ["controller_model.inertia_scale[1]"]),
        ("flc.position_rate_share", 1.5, ["flc.position_rate_share", "[0, 1]"]),
        ("motors.thrust_loop_time_constant", -1.0, ["motors.thrust_loop_time_constant", "[0, 10000] s"]),
        ("motors.thrust_loop_time_constant", 0.5, ["motors.thrust_loop_time_constant", "must be 0 (open loop)"]),
        ("motors.thrust_loop_limit_grf", 900.0, ["motors.thrust_loop_limit_grf", "[0, 850] gr.F"]),
    ],
)
def test_bad_values_name_the_key_and_range(key, value, words):
    with pytest.raises(ConfigError) as err:
        load_config(overrides={key: value})
    for w in words:
        assert w in str(err.value)


def test_unknown_key_suggests_the_nearest():
    with pytest.raises(ConfigError, match="did you mean 'smc.switching'"):
        load_config(overrides={"smc.swiching": "sgn"})


def test_unknown_presets_list_the_choices():
    with pytest.raises(ConfigError, match="hilms"):
        load_config(airframe="crazyflie")
    with pytest.raises(ConfigError, match="helix"):
        load_config(scenario="loop-the-loop")


def test_user_file_layers_and_broken_file(tmp_path):
    good = tmp_path / "gains.toml"
    good.write_text("[smc]\nswitching = 'boundary'\nboundary_layer = 0.2\n")
    cfg = load_config(files=[good])
    assert cfg["smc.switching"] == "boundary" and cfg["smc.boundary_layer"] == 0.2
    bad = tmp_path / "broken.toml"
    bad.write_text("[smc\nk = 1")
    with pytest.raises(ConfigError, match="broken.toml: not valid TOML"):
        load_config(files=[bad])


def test_parse_override_takes_toml_values_and_bare_words():
    assert parse_override("smc.k=[2, 2, 2]") == ("smc.k", [2, 2, 2])
    assert parse_override("control.strategy=flc") == ("control.strategy", "flc")
    assert parse_override("sim.ground=false") == ("sim.ground", False)
    with pytest.raises(ConfigError):
        parse_override("no-equals-sign")


def test_waypoint_guidance_needs_waypoints():
    with pytest.raises(ConfigError, match="guidance.waypoints"):
        load_config(overrides={"guidance.type": "waypoints", "guidance.waypoints": []})


def test_hilms_is_hilms_ideal_plus_its_hardware_preset():
    """The default airframe is the hardware rig; ``hilms-ideal`` has every effect neutral."""
    hw, ideal = load_config("hilms"), load_config("hilms-ideal")
    differ = {k for k in SCHEMA if hw[k] != ideal[k]}
    # the virtual ground's resting contact is a reading of the hardware rig (physics/ground.py), kept beside sim.ground
    assert hw["sim.ground_contact"] == "hold" and ideal["sim.ground_contact"] == "frictionless"
    assert differ and all(not k.startswith(("airframe.", "sim.", "guidance."))
                          for k in differ - {"airframe.name", "sim.ground_contact"})
    assert ideal["joint.viscous"] == [0.0, 0.0, 0.0] and ideal["smc.gain_reading"] == "si"
    assert ideal["motors.curve_exponent"] == 1.0 and ideal["control.actuation_delay"] == 0.0
    assert load_config()["airframe.name"] == "hilms"
    # user layers still win over the hardware preset
    assert load_config("hilms", overrides={"joint.viscous": [0.0, 0.0, 0.0]})["joint.viscous"] == [0.0, 0.0, 0.0]


def test_airframe_preset_keys_based_on_and_hardware_are_checked(tmp_path, monkeypatch):
    from rig_emulator.config import loader

    root = tmp_path / "presets"
    (root / "airframes").mkdir(parents=True)
    (root / "hardware").mkdir()
    (root / "rig.toml").write_text((loader._preset_dir() / "rig.toml").read_text())
    (root / "airframes" / "base.toml").write_text((loader._preset_dir("airframes") / "hilms-ideal.toml").read_text())
    (root / "airframes" / "rig.toml").write_text('based_on = "base"\nhardware = "mine"\nmass = 3.0\n')
    (root / "airframes" / "loop.toml").write_text('based_on = "loop"\n')
    (root / "airframes" / "nohw.toml").write_text('based_on = "base"\nhardware = "missing"\n')
    (root / "hardware" / "mine.toml").write_text("[joint]\nviscous = [0.1, 0.1, 0.1]\n")
    monkeypatch.setattr(loader, "_preset_dir", lambda kind=None: root / kind if kind else root)
    loader._parsed_preset.cache_clear()
    loader._validated_presets.cache_clear()
    loader._base_preset.cache_clear()
    try:
        cfg = load_config("rig")
        assert cfg["airframe.mass"] == 3.0 and cfg["airframe.ixx"] == 6.2e-2 and cfg["joint.viscous"] == [0.1] * 3
        with pytest.raises(ConfigError, match="loop"):
            load_config("loop")
        with pytest.raises(ConfigError, match="missing"):
            load_config("nohw")
    finally:
        loader._parsed_preset.cache_clear()
        loader._validated_presets.cache_clear()
        loader._base_preset.cache_clear()
