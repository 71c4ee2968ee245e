"""PX4's custom_mode packing, checked against pymavlink's independent table of PX4 modes."""

from pymavlink import mavutil

from protocol.dialect import mavlink as M
from protocol.px4_custom_mode import custom_mode, split_custom_mode


def test_every_px4_mode_packs_as_pymavlink_reads_it():
    for name, (_, main, sub) in mavutil.px4_map.items():
        value = custom_mode(main, sub)
        assert split_custom_mode(value) == (main, sub)
        hb = M.MAVLink_heartbeat_message(M.MAV_TYPE_QUADROTOR, M.MAV_AUTOPILOT_PX4,
                                         M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, value, M.MAV_STATE_STANDBY, 3)
        assert mavutil.mode_string_v10(hb) == name


def test_split_ignores_the_low_bits():
    assert split_custom_mode(custom_mode(4, 3) | 0xFFFF) == (4, 3)
