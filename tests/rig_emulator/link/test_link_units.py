"""Link building blocks without sockets: units, set-point frames, schedules, modes, MAVFTP."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from protocol.dialect import mavlink as M
from protocol.frames import mavlink_quaternion_from_rwb, rwb_from_paper_euler
from rig_emulator.link.ftp import server as ftp
from rig_emulator.link.telemetry import units as U
from rig_emulator.link.commands.command_long import Command
from rig_emulator.link.commands.modes import AUTO, AUTO_MISSION, POSCTL, FlightModes, custom_mode, split_custom_mode
from rig_emulator.link.commands.offboard_setpoints import rwb_from_mavlink_quaternion
from rig_emulator.link.telemetry.streams import StreamSchedule
from rig_emulator.link.telemetry.attitude import body_rates_from_paper_euler_rates
from rig_emulator.physics.rotation import euler_rates_from_body_rates


def test_units_saturate_and_never_cast_nan():
    assert U.mm(1.2345) == 1234 or U.mm(1.2345) == 1235
    assert U.milli_g(9.80665) == 1000
    assert U.milli_g(1e6) == 32767 and U.milli_g(-1e6) == -32768
    assert U.mm(math.nan) == 0
    assert U.heading_rad_to_cdeg(math.nan) == U.UINT16_UNKNOWN
    assert U.heading_rad_to_cdeg(-math.pi / 2) == 27000
    assert U.pwm_us(0.0, 15.0) == 1000 and U.pwm_us(15.0, 15.0) == 2000 and U.pwm_us(7.5, 15.0) == 1500
    assert U.pwm_us(99.0, 15.0) == 2000 and U.pwm_us(math.nan, 15.0) == 1000
    assert U.time_boot_ms(1_234_567) == 1234 and U.time_usec(1_234_567) == 1_234_567
    assert U.time_boot_ms(2**32 * 1000 + 5000) == 5 and U.time_usec_u32(2**32 + 7) == 7
    assert U.deg_e7(35.7) == 357000000


angles = st.floats(-1.2, 1.2)


@settings(max_examples=60, deadline=None)
@given(angles, angles, st.floats(-3.0, 3.0))
def test_attitude_setpoint_quaternion_round_trip(phi, theta, psi):
    """A SET_ATTITUDE_TARGET quaternion (NED/FRD) maps back to the paper's R_WB."""
    r_wb = rwb_from_paper_euler(phi, theta, psi)
    q = mavlink_quaternion_from_rwb(r_wb)
    np.testing.assert_allclose(rwb_from_mavlink_quaternion(q), r_wb, atol=1e-9)
    np.testing.assert_allclose(rwb_from_mavlink_quaternion(-2.0 * q), r_wb, atol=1e-9)  # sign and scale free


@settings(max_examples=60, deadline=None)
@given(angles, angles, st.floats(-2, 2), st.floats(-2, 2), st.floats(-2, 2))
def test_body_rates_invert_the_euler_kinematics(phi, theta, wx, wy, wz):
    rates = euler_rates_from_body_rates(phi, theta, wx, wy, wz)
    back = body_rates_from_paper_euler_rates((phi, theta, 0.0), rates)
    np.testing.assert_allclose(back, (wx, wy, wz), atol=1e-9)


def test_schedule_counts_exactly_in_simulated_time():
    s = StreamSchedule({1: 25.0, 2: 3.0, 3: 0.0}, min_interval_s=0.005)
    counts = {1: 0, 2: 0, 3: 0}
    for k in range(1, 2001):  # 10 s in 5 ms chunks
        for msg_id in s.due(k * 0.005):
            counts[msg_id] += 1
    assert abs(counts[1] - 250) <= 1 and abs(counts[2] - 30) <= 1 and counts[3] == 0
    s.set_interval(1, -1, now=10.0)
    assert s.interval_us(1) == -1 and 1 not in s.due(20.0)
    s.set_interval(1, 0, now=10.0)
    assert s.interval_us(1) == 40000
    s.set_interval(1, 100, now=10.0)  # 10 kHz asked: raised to the service period
    assert s.interval_us(1) == 5000


def test_modes_pack_like_px4():
    assert custom_mode(POSCTL, 0) == 3 << 16
    assert split_custom_mode(custom_mode(AUTO, AUTO_MISSION)) == (AUTO, AUTO_MISSION)
    modes = FlightModes()
    assert modes.name == "POSCTL"
    assert not modes.enter(AUTO, AUTO_MISSION, rig=None)  # the mission issue registers it
    assert modes.name == "POSCTL"
    entered = []
    modes.register(AUTO, AUTO_MISSION, entered.append)
    assert modes.enter(AUTO, AUTO_MISSION, rig="rig") and entered == ["rig"] and modes.name == "AUTO.MISSION"


def test_nan_command_params_are_unset():
    msg = M.MAVLink_command_long_message(1, 1, 400, 0, 1.0, math.nan, math.nan, math.nan, math.nan, math.inf, 2.0)
    cmd = Command.from_long(msg)
    assert cmd.params == (1.0, None, None, None, None, None, 2.0)
    assert cmd.int_param(1) == 1 and cmd.int_param(2) is None


def test_ftp_param_pck_gets_a_nak_with_the_next_seq():
    req = bytes([7, 0, 0, 4, 16, 0, 0, 0, 0, 0, 0, 0]) + b"@PARAM/param.pck"
    msg = M.MAVLink_file_transfer_protocol_message(0, 1, 1, list(req.ljust(251, b"\0")))
    msg._header = M.MAVLink_header(msg.id, srcSystem=255, srcComponent=190)
    (payload,) = ftp.FtpServer(ftp.FileStore({})).handle(bytes(msg.payload))
    reply = ftp.reply_message(payload, msg)
    payload = bytes(reply.payload)
    seq, session, opcode, size, req_opcode = ftp.HEADER.unpack_from(payload)[:5]
    assert (seq, opcode, size, req_opcode, payload[12]) == (8, ftp.OP_NAK, 1, 4, ftp.ERR_FILE_NOT_FOUND)
    assert reply.target_system == 255


@pytest.mark.parametrize("spec", ["serial:/dev/ttyS0", "udpout:127.0.0.1", "tcpin:host:99999", "nonsense"])
def test_bad_connection_strings_are_refused(spec):
    from rig_emulator.link.endpoints.sockets import EndpointError, open_endpoint

    with pytest.raises(EndpointError):
        open_endpoint(spec)
