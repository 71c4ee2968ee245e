"""CSV column names end with their unit, the project's `thrust_grf` / `phi_deg` convention."""

from protocol.column_units import unit_token, with_unit


def test_unit_tokens_survive_csv_readers():
    assert [unit_token(u) for u in ("m/s", "N m", "rad/s", "%", "m/s*5", "m/s/s", "")] == \
        ["m_s", "Nm", "rad_s", "pct", "m_sx5", "m_s_s", ""]


def test_names_get_their_unit_once():
    assert with_unit("pos_0", "m") == "pos_0_m"
    assert with_unit("ATTITUDE.roll", "rad") == "ATTITUDE.roll_rad"
    assert with_unit("ATTITUDE.time_boot_ms", "ms") == "ATTITUDE.time_boot_ms"
    assert with_unit("HILMS_LOAD_CELLS.thrust_n[2]", "N") == "HILMS_LOAD_CELLS.thrust_n[2]"
    assert with_unit("HILMS_LOAD_CELLS.force_grf[0]", "gf") == "HILMS_LOAD_CELLS.force_grf[0]"
    assert with_unit("GLOBAL_POSITION_INT.lat", "degE7") == "GLOBAL_POSITION_INT.lat_degE7"
    assert with_unit("mode", "") == with_unit("mode", None) == "mode"


def test_every_series_of_the_log_has_a_unit_entry():
    from rig_emulator.headless.series_files import UNITS, csv_columns
    from rig_emulator.simulation import log_layout as L

    assert set(UNITS) == set(L.NAMES)
    for name, (_, width) in L.NAMES.items():
        assert not isinstance(UNITS[name], tuple) or len(UNITS[name]) == width, name
    _, names = csv_columns()
    assert names[:4] == ["t_s", "pos_0_m", "pos_1_m", "pos_2_m"] and len(set(names)) == len(names)

