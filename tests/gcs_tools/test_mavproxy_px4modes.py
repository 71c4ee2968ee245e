"""The MAVProxy mode module's name and number reading (the module itself is flown with a real
MAVProxy in tests/rig_emulator/link/test_link_modes_mavproxy.py)."""

from pymavlink import mavutil

from gcs_tools.mavproxy_px4modes import px4_mode_triple
from rig_emulator.link.commands import modes as MD


def test_every_listed_name_and_its_custom_mode_number_give_the_same_main_and_sub_mode():
    for name, (base, main, sub) in mavutil.px4_map.items():
        assert px4_mode_triple(name) == (base, main, sub)
        assert px4_mode_triple(name.lower()) == (base, main, sub)
        custom = (main << 16) | (sub << 24)
        assert MD.split_custom_mode(custom) == (main, sub)
        assert px4_mode_triple(str(custom))[1:] == (main, sub)
    assert px4_mode_triple("GUIDED") is None and px4_mode_triple("-1") is None


def test_the_rigs_own_mode_is_named_as_the_rig_reports_it():
    base, main, sub = px4_mode_triple("sysid")
    assert base == mavutil.mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert MD.custom_mode(main, sub) == MD.custom_mode(MD.AUTO, MD.AUTO_SYSID)
    assert MD.MODES[(main, sub)].name == "AUTO.SYSID"
