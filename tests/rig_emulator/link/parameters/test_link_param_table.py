"""The MAVLink parameter table built from the schema."""

import math

import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.config.schema import SCHEMA, STRATEGIES
from rig_emulator.link.parameters.table import EXCLUDED, SHORT_NAMES, ParamTable, build_table, unmapped_keys


def test_every_schema_key_is_named_or_excluded():
    assert unmapped_keys() == []
    assert not set(SHORT_NAMES) & set(EXCLUDED)
    assert set(SHORT_NAMES) | set(EXCLUDED) <= set(SCHEMA)


def test_names_unique_short_and_indexes_dense():
    table = build_table()
    names = [p.name for p in table]
    assert len(names) == len(set(names))
    assert all(1 <= len(n) <= 16 and n.isascii() and n == n.upper() for n in names)
    assert [p.index for p in table] == list(range(len(table)))
    assert build_table() == table  # stable across builds


def test_examples_from_the_documentation():
    t = ParamTable()
    assert t.by_name["SMC_K_PHI"].key == "smc.k" and t.by_name["SMC_K_PHI"].element == 0
    assert t.by_name["SMC_K_PSI"].element == 2
    assert t.by_name["FLC_D1_PHI"].key == "flc.d1_phi_deg"
    assert t.by_name["WP_RADIUS"].key == "guidance.switching_radius"
    assert t.by_name["FLC_R4"].element == 3


def test_values_follow_the_config():
    cfg = load_config(overrides={"control.strategy": "pid", "smc.k": [1.0, 2.0, 3.0]})
    t = ParamTable()
    assert t.by_name["CTL_STRATEGY"].value(cfg) == STRATEGIES.index("pid")
    assert t.by_name["SMC_K_THE"].value(cfg) == 2.0
    assert t.by_name["SIM_GROUND"].value(cfg) in (0.0, 1.0)
    for p in t.params:
        assert math.isfinite(p.value(cfg))


def test_wire_values_become_config_values():
    cfg = load_config()
    t = ParamTable()
    assert t.by_name["CTL_STRATEGY"].to_config(1.0, cfg) == STRATEGIES[1]
    assert t.by_name["SMC_K_THE"].to_config(5.0, cfg) == [cfg["smc.k"][0], 5.0, cfg["smc.k"][2]]
    assert t.by_name["SIM_GROUND"].to_config(0.0, cfg) is False
    with pytest.raises(ValueError, match="index 0..3"):
        t.by_name["CTL_STRATEGY"].to_config(4.0, cfg)
    with pytest.raises(ValueError, match="index"):
        t.by_name["CTL_STRATEGY"].to_config(1.5, cfg)
    with pytest.raises(ValueError, match="finite"):
        t.by_name["SMC_BL"].to_config(float("nan"), cfg)
    with pytest.raises(ValueError, match="0 or 1"):
        t.by_name["SIM_GROUND"].to_config(2.0, cfg)


def test_lookup_by_index_and_name():
    t = ParamTable()
    assert t.lookup("ignored", 3) is t.params[3]
    assert t.lookup("WP_RADIUS", -1).name == "WP_RADIUS"
    assert t.lookup("NOPE", -1) is None
    assert t.lookup("", len(t)) is None
