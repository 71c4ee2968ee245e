"""A controller plug-in's parameters in the MAVLink parameter table and the component metadata."""

import json

import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.controllers import Controller, PluginError
from rig_emulator.controllers.examples.hover import LevelHover
from rig_emulator.link.ftp.component_metadata import general_metadata, parameter_metadata, crc32
from rig_emulator.link.parameters.table import ParamTable, describe
from rig_emulator.simulation.live import LiveRig


class Ranged(LevelHover):
    param_prefix = "RNG_"
    params = {**LevelHover.params, "gains": [1.0, 2.0, 3.0]}
    param_info = {"kp_z": {"min": 0.0, "max": 20.0, "unit": "1/s^2", "doc": "altitude stiffness"}}


def test_names_indexes_and_values_follow_the_rigs_table():
    ctrl = Ranged()
    base, table = ParamTable(), ParamTable(ctrl)
    extra = table.params[len(base):]
    assert [p.name for p in extra] == ["RNG_KP_ATT", "RNG_KD_ATT", "RNG_KP_Z", "RNG_KD_Z", "RNG_GAINS1", "RNG_GAINS2",
                                       "RNG_GAINS3"]
    assert [p.index for p in extra] == list(range(len(base), len(table)))
    assert table.lookup("RNG_GAINS2", -1).value() == 2.0 and table.lookup(None, len(table) - 1).name == "RNG_GAINS3"
    assert "165 RNG_GAINS3       controller.params.gains[2]".split()[1:] == describe(table).splitlines()[-1].split()[1:]
    p = table.by_name["RNG_KP_Z"]
    assert p.to_config(5.0, None)["kp_z"] == 5.0
    with pytest.raises(ValueError, match=r"RNG_KP_Z: 25 is outside \[0, 20\]"):
        p.to_config(25.0, None)


@pytest.mark.parametrize("prefix, params, words", [
    ("myc_", {"k": 1.0}, "param_prefix = 'myc_'"),
    ("MYC", {"k": 1.0}, "end with '_'"),
    ("MYCONTROLLER_", {"gain_one": 1.0}, "longer than 16 characters"),
    ("SMC_", {"k_phi": 1.0}, "'SMC_K_PHI', which is taken"),
])
def test_bad_declarations_are_refused_with_the_reason(prefix, params, words):
    cls = type("Bad", (Controller,), {"param_prefix": prefix, "params": params})
    with pytest.raises(PluginError, match="Bad") as err:
        ParamTable(cls())
    assert words in str(err.value)


def test_the_component_metadata_describes_them():
    ctrl = Ranged(kp_z=7.0)
    doc = json.loads(parameter_metadata(ctrl))
    entry = next(e for e in doc["parameters"] if e["name"] == "RNG_KP_Z")
    assert entry["default"] == 4.0 and entry["min"] == 0 and entry["max"] == 20 and entry["units"] == "1/s^2"
    assert entry["shortDesc"] == "altitude stiffness" and "controller plug-in" in entry["group"]
    assert len(doc["parameters"]) == len(ParamTable(ctrl))
    general = json.loads(general_metadata(ctrl))
    assert general["metadataTypes"][0]["fileCrc"] == crc32(parameter_metadata(ctrl)) != crc32(parameter_metadata())


def test_config_values_are_checked_against_the_declared_range():
    cfg = load_config(scenario="hover", overrides={"controller.params": {"kp_z": 30.0}})
    with pytest.raises(PluginError, match=r"controller.params.kp_z = 30.0: must be in \[0, 20\] 1/s\^2"):
        LiveRig(cfg, controller=Ranged)
