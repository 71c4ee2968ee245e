"""Parameter keys, bounds and priors of rig-gcs identify: what is accepted, what is refused and why."""

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcs_tools.identify.params import merge, overrides_for, parse_params_arg, parse_prior_arg, params_from_spec, start_values
from rig_emulator.config.loader import ConfigError, load_config


def test_scalar_element_table_field_and_tree_leaf_keys():
    (k,) = parse_params_arg("smc.k[1]=0.5:3")
    (tc,) = parse_params_arg("motors.time_constant=0.01:0.2:0.04")
    (leaf,) = parse_params_arg("sensor_models.mpu6050.gyro.noise_dps_per_rthz=0.001:0.02")
    assert (k.key.kind, k.key.elements, tc.start, leaf.key.path) == ("element", (1,), 0.04, ("gyro", "noise_dps_per_rthz"))
    cfg = load_config(scenario="extra-mass")
    (mass,) = parse_params_arg("disturbance.extra_masses[0].mass=0:0.2")
    ov = overrides_for([k, tc, leaf, mass], [2.0, 0.07, 0.005, 0.15], cfg)
    assert ov["smc.k"] == [cfg["smc.k"][0], 2.0, cfg["smc.k"][2]]
    assert ov["motors.time_constant"] == 0.07
    assert ov["sensor_models.mpu6050"]["gyro"]["noise_dps_per_rthz"] == 0.005
    assert ov["disturbance.extra_masses"][0]["mass"] == 0.15
    assert ov["disturbance.extra_masses"][1] == cfg["disturbance.extra_masses"][1]
    fitted = load_config(scenario="extra-mass", overrides=ov)  # the loader takes them
    assert fitted["smc.k"][1] == 2.0 and cfg["smc.k"][1] != 2.0  # the base is not changed
    # start: the configured value when inside the bounds, else mid-range; an explicit start wins
    assert start_values([k, tc], cfg) == [cfg["smc.k"][1], 0.04]
    (far,) = parse_params_arg("smc.k[1]=5:7")
    assert start_values([far], cfg) == [6.0]


def test_tied_elements_take_one_value():
    tied, lam = parse_params_arg("smc.k[0,1]=0.5:3,smc.lam[2]=0:1")
    assert tied.key.elements == (0, 1) and lam.name == "smc.lam[2]"
    cfg = load_config()
    ov = overrides_for([tied, lam], [2.5, 0.3], cfg)
    assert ov["smc.k"] == [2.5, 2.5, cfg["smc.k"][2]] and ov["smc.lam"][2] == 0.3


@pytest.mark.parametrize("text, words", [
    ("smc.kk[0]=0:1", ["unknown parameter", "did you mean 'smc.k'"]),
    ("smc.k=0:1", ["is a list", "smc.k[0]"]),
    ("smc.k[3]=0:1", ["3 elements"]),
    ("smc.k[0,0]=0:1", ["named twice"]),
    ("disturbance.extra_masses[0,1].mass=0:1", ["one entry"]),
    ("smc.k[0]=-1:1", ["smc.k[0]", "lower bound", "[0, 10000]"]),
    ("airframe.ixx=0:1", ["airframe.ixx", "(0, 100]"]),
    ("airframe.ixx=0.05:200", ["upper bound", "(0, 100]"]),
    ("sim.seed=0:3", ["integer"]),
    ("smc.switching=0:1", ["not a number"]),
    ("motors.time_constant=0.2:0.1", ["below the upper bound"]),
    ("motors.time_constant=0:0.1:0.3", ["start 0.3", "outside the bounds"]),
    ("motors.time_constant=a:1", ["not a number"]),
    ("motors.time_constant", ["expected KEY=LO:HI"]),
    ("sensor_models.mpu6050.gyro.nope=0:1", ["unknown key"]),
])
def test_bad_parameters_are_refused_naming_the_key(text, words):
    with pytest.raises(ConfigError) as info:
        parse_params_arg(text)
    for w in words:
        assert w in str(info.value)


def test_priors_and_spec_tables():
    params = params_from_spec({"param": [{"key": "smc.k[0]", "lo": 0.5, "hi": 3.0, "prior": [1.5, 0.2]},
                                         {"key": "motors.time_constant", "lo": 0.01, "hi": 0.2}]}, "spec.toml")
    assert params[0].prior == (1.5, 0.2)
    merged = merge(params, {"motors.time_constant": parse_prior_arg("motors.time_constant=0.05+-0.01")[1]})
    assert merged[1].prior == (0.05, 0.01)
    with pytest.raises(ConfigError, match="not among the fitted"):
        merge(params, {"smc.lam[0]": (1.0, 1.0)})
    with pytest.raises(ConfigError, match="given twice"):
        merge(params + params[:1], {})
    with pytest.raises(ConfigError, match="unknown field"):
        params_from_spec({"param": [{"key": "smc.k[0]", "lo": 0, "hi": 1, "stride": 1}]}, "spec.toml")
    (d,) = params_from_spec({"param": [{"key": "control.actuation_delay", "lo": 0, "hi": 0.02, "step": 0.001}]}, "s")
    assert d.step == 0.001
    with pytest.raises(ConfigError, match="at most half the range"):
        params_from_spec({"param": [{"key": "control.actuation_delay", "lo": 0, "hi": 0.02, "step": 0.015}]}, "s")
    with pytest.raises(ConfigError, match="sigma"):
        params_from_spec({"param": [{"key": "smc.k[0]", "lo": 0, "hi": 1, "prior": [0.5, 0]}]}, "spec.toml")


@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])  # math only: a loaded CI machine is no failure
@given(lo=st.floats(0.0, 10.0), width=st.floats(1e-3, 10.0), z=st.floats(0.0, 1.0))
def test_unit_mapping_round_trips_inside_the_bounds(lo, width, z):
    (p,) = parse_params_arg(f"smc.lam[0]={lo!r}:{lo + width!r}")
    v = p.from_unit(z)
    assert p.lo <= v <= p.hi
    assert p.to_unit(v) == pytest.approx(z, abs=1e-9)
