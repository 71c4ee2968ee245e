"""Every command is ACKed at once: supported ones act, unknown ones are UNSUPPORTED."""

import struct

import pytest

from protocol.dialect import mavlink as M
from rig_emulator.link.ftp import server as ftp
from rig_emulator.testing.rig import NAN, command, recv

ACCEPTED, DENIED, UNSUPPORTED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED, M.MAV_RESULT_UNSUPPORTED


def test_unknown_commands_are_unsupported(client):
    assert command(client, 31999).result == UNSUPPORTED
    assert command(client, M.MAV_CMD_DO_ORBIT).result == UNSUPPORTED
    # a barometer calibration has no barometer to calibrate
    assert command(client, M.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 1, 0, 0, 0, 0).result == UNSUPPORTED


def test_sensor_fault_reaches_the_module_and_its_telemetry(rig, client):
    result = command(client, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, 1, M.HILMS_FAULT_DEAD, 0)
    assert result.result == ACCEPTED
    msg = recv(client, "HILMS_IMU_MODULE", condition=lambda m: m.module_index == 1 and m.fault == M.HILMS_FAULT_DEAD)
    assert list(msg.gyro_raw) == [0, 0, 0] and list(msg.accel_raw) == [0, 0, 0]
    assert rig.server.rig.snapshot().sensors.imu_fault_modes[1] == 2
    assert command(client, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_LOAD_CELL, 2, M.HILMS_FAULT_SPIKE, 40).result == ACCEPTED
    assert rig.server.rig.snapshot().sensors.cell_fault_modes[1] == 5
    assert command(client, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, 9, M.HILMS_FAULT_DEAD, 0).result == DENIED
    assert command(client, M.MAV_CMD_HILMS_SENSOR_FAULT, M.HILMS_SENSOR_KIND_IMU_MODULE, 1, M.HILMS_FAULT_NONE, 0).result == ACCEPTED
    assert rig.server.rig.snapshot().sensors.imu_fault_modes[1] == 0


def test_preflight_calibration_reruns_the_procedure_when_disarmed(rig, client):
    before = rig.server.rig.sim.sensing.params.chain.cal.gain.copy()
    assert command(client, M.MAV_CMD_PREFLIGHT_CALIBRATION, 1, 0, 0, 0, 0, 0, 0).result == ACCEPTED
    assert recv(client, "STATUSTEXT", condition=lambda m: "calibration done" in m.text) is not None
    after = rig.server.rig.sim.sensing.params.chain.cal.gain
    assert not (before == after).all()  # a new procedure, new noise: a new (close) result
    assert abs(after - before).max() < 0.01 * abs(before).max()
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    assert command(client, M.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 1, 0, 0).result == DENIED


def test_duplicates_each_get_an_ack(rig, client):
    for confirmation in range(5):  # MAVSDK-style retries
        client.mav.command_long_send(1, 1, M.MAV_CMD_HILMS_SHOCK, confirmation, 1, 0.2, 0.05, NAN, NAN, NAN, NAN)
    acks = [recv(client, "COMMAND_ACK") for _ in range(5)]
    assert [a.result for a in acks] == [ACCEPTED] * 5
    assert rig.server.rig.sim.dist.shocks.shape[0] >= 1
    for _ in range(3):  # plain repeats too
        client.mav.command_long_send(1, 1, 31999, 0, *[NAN] * 7)
    assert [recv(client, "COMMAND_ACK").result for _ in range(3)] == [UNSUPPORTED] * 3


def test_nan_params_are_unset_not_cast(client):
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, NAN).result == DENIED
    assert command(client, M.MAV_CMD_HILMS_SHOCK, 1, NAN, 0.1).result == DENIED
    assert command(client, M.MAV_CMD_REQUEST_MESSAGE, NAN).result == UNSUPPORTED
    assert command(client, M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE, NAN).result == DENIED
    assert command(client, M.MAV_CMD_HILMS_SHOCK, 9, 0.2, 0.1).result == DENIED
    assert recv(client, "STATUSTEXT", condition=lambda m: "shock" in m.text) is not None
    assert recv(client, "ATTITUDE") is not None  # still streaming


def _next_message(conn):
    return recv(conn, None)


def test_arming_heartbeat_follows_at_once(client):
    """The message right after the ACK is a HEARTBEAT showing the new state."""
    ack = command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert ack.result == ACCEPTED
    hb = _next_message(client)
    assert hb.get_type() == "HEARTBEAT" and hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED
    assert hb.system_status == M.MAV_STATE_ACTIVE
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 0).result == ACCEPTED
    hb = _next_message(client)
    assert hb.get_type() == "HEARTBEAT" and not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED


def test_request_message_and_capabilities(client):
    assert command(client, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION).result == ACCEPTED
    ver = recv(client, "AUTOPILOT_VERSION")
    need = (M.MAV_PROTOCOL_CAPABILITY_MISSION_INT | M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | M.MAV_PROTOCOL_CAPABILITY_MAVLINK2 | M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT)
    assert ver.capabilities & need == need
    assert command(client, M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1).result == ACCEPTED
    assert recv(client, "AUTOPILOT_VERSION") is not None
    assert command(client, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_HOME_POSITION).result == ACCEPTED
    assert recv(client, "HOME_POSITION") is not None
    assert command(client, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_HILMS_CONTROLLER_STATE).result == ACCEPTED
    assert recv(client, "HILMS_CONTROLLER_STATE") is not None
    assert command(client, M.MAV_CMD_REQUEST_MESSAGE, 12345).result == UNSUPPORTED


def test_command_int_is_acked_like_command_long(client):
    client.mav.command_int_send(1, 1, M.MAV_FRAME_GLOBAL, M.MAV_CMD_REQUEST_MESSAGE, 0, 0,
                                M.MAVLINK_MSG_ID_HOME_POSITION, NAN, NAN, NAN, 0, 0, NAN)
    ack = recv(client, "COMMAND_ACK", condition=lambda m: m.command == M.MAV_CMD_REQUEST_MESSAGE)
    assert ack.result == ACCEPTED
    client.mav.command_int_send(1, 1, M.MAV_FRAME_GLOBAL, 31999, 0, 0, NAN, NAN, NAN, NAN, 0, 0, NAN)
    assert recv(client, "COMMAND_ACK", condition=lambda m: m.command == 31999).result == UNSUPPORTED


def test_set_mode_px4_layout(client):
    base = M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert command(client, M.MAV_CMD_DO_SET_MODE, base, 7).result == ACCEPTED  # STABILIZED
    assert _next_message(client).custom_mode == 7 << 16
    assert command(client, M.MAV_CMD_DO_SET_MODE, base, 4, 4).result == DENIED  # AUTO.MISSION without a mission
    assert command(client, M.MAV_CMD_DO_SET_MODE, base, 3).result == ACCEPTED  # POSCTL
    assert _next_message(client).custom_mode == 3 << 16
    assert command(client, M.MAV_CMD_DO_SET_MODE, 0, 3).result == DENIED


def test_timesync_and_ftp_answers(client):
    client.mav.timesync_send(0, 123456789)
    ts = recv(client, "TIMESYNC")
    assert ts.ts1 == 123456789 and ts.tc1 > 0
    req = struct.pack("<HBBBBBBI", 1, 0, ftp.OP_OPEN_FILE_RO, 16, 0, 0, 0, 0) + b"@PARAM/param.pck"
    client.mav.file_transfer_protocol_send(0, 1, 1, list(req.ljust(251, b"\0")))
    reply = recv(client, "FILE_TRANSFER_PROTOCOL")
    assert bytes(reply.payload)[3] == ftp.OP_NAK and bytes(reply.payload)[0] == 2


def test_extra_mass_command(rig, client):
    assert command(client, M.MAV_CMD_HILMS_EXTRA_MASS, 2, 0.07, 0.33).result == ACCEPTED
    assert rig.server.rig.sim.dist.extra[1, 0] == pytest.approx(0.07, rel=1e-6)
    assert command(client, M.MAV_CMD_HILMS_EXTRA_MASS, 2, 50.0, 0.33).result == DENIED
