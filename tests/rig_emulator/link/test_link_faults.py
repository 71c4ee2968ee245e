"""Faults over MAVLink: MAV_CMD_HILMS_SENSOR_FAULT, SYS_STATUS health, STATUSTEXT once, failsafe."""

import time

import pytest

from protocol.dialect import mavlink as M
from rig_emulator.testing.rig import RigThread, command, connect, recv, recv_text

ACCEPTED, DENIED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED
FAULT = M.MAV_CMD_HILMS_SENSOR_FAULT
IMU, CELL, MOTOR = M.HILMS_SENSOR_KIND_IMU_MODULE, M.HILMS_SENSOR_KIND_LOAD_CELL, M.HILMS_SENSOR_KIND_MOTOR
CONTROL = M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL | M.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION


@pytest.fixture
def rig():
    """The link conftest's rig at 8x (its ``client`` fixture connects to this one)."""
    with RigThread(speedup=8.0) as r:
        yield r


def _texts_for(client, wall_s: float) -> list[str]:
    """Every STATUSTEXT (chunks joined) received during ``wall_s`` seconds."""
    out, deadline = [], time.monotonic() + wall_s
    while time.monotonic() < deadline:
        got = recv_text(client, timeout=max(deadline - time.monotonic(), 0.01))
        if got is not None:
            out.append(got[1])
    return out


def _text(client, condition):
    got = recv_text(client, condition)
    assert got is not None, "STATUSTEXT not received"
    return got


def _sys_status(client, condition):
    return recv(client, "SYS_STATUS", condition=lambda m: condition(m.onboard_control_sensors_health))


def test_imu_fault_by_command_is_reported_once_and_in_the_health_bits(client):
    assert _sys_status(client, lambda h: h & M.MAV_SYS_STATUS_PREARM_CHECK) is not None  # all healthy first
    assert command(client, FAULT, IMU, 1, M.HILMS_FAULT_DEAD).result == ACCEPTED
    severity, _ = _text(client, lambda t: t == "IMU module 1: dead injected")
    assert severity == M.MAV_SEVERITY_WARNING
    _, detected = _text(client, lambda t: t.startswith("ensemble rejects IMU module 1"))
    assert "accel" in detected
    # the module array lost a module (ACCEL2 red), the fused estimate the rig flies on is fine (ACCEL green)
    st = _sys_status(client, lambda h: not h & M.MAV_SYS_STATUS_SENSOR_3D_ACCEL2)
    h = st.onboard_control_sensors_health
    assert h & M.MAV_SYS_STATUS_SENSOR_3D_ACCEL and h & M.MAV_SYS_STATUS_AHRS
    assert not h & M.MAV_SYS_STATUS_PREARM_CHECK
    later = _texts_for(client, 0.6)  # about 5 s of simulated time: no repeats
    assert not any("IMU module 1" in t for t in later), later
    assert command(client, FAULT, IMU, 1, M.HILMS_FAULT_NONE).result == ACCEPTED
    assert _text(client, lambda t: t == "IMU module 1: fault cleared") is not None
    assert _text(client, lambda t: t == "ensemble accepts IMU module 1 again") is not None
    assert _sys_status(client, lambda h: h & M.MAV_SYS_STATUS_PREARM_CHECK) is not None


def test_bad_fault_arguments_are_denied_with_a_reason(client):
    bad = [
        ((IMU, 5, M.HILMS_FAULT_DEAD), "IMU module 5: must be 0..4"),
        ((CELL, 0, M.HILMS_FAULT_DEAD), "load cell 0: must be 1..4"),
        ((MOTOR, 1, M.HILMS_FAULT_THRUST_LOSS, 1.5), "must be in [0, 1]"),
        ((MOTOR, 1, M.HILMS_FAULT_THRUST_LOSS, -0.1), "must be in [0, 1]"),
        ((MOTOR, 1, M.HILMS_FAULT_THRUST_LOSS), "needs a magnitude"),
        ((IMU, 2, M.HILMS_FAULT_SPIKE, 100.0), "does not apply to an IMU module"),
        ((MOTOR, 2, M.HILMS_FAULT_STUCK), "does not apply to a motor"),
        ((7, 1, M.HILMS_FAULT_DEAD), "kind 7 unknown"),
        ((IMU, 1, 42), "fault 42 unknown"),
        ((IMU, 1.5, M.HILMS_FAULT_DEAD), "must be whole numbers"),
    ]
    for params, reason in bad:
        ack = command(client, FAULT, *params)
        assert ack.result == DENIED, params
        _, text = _text(client, lambda t: t.startswith("fault rejected"))
        assert reason in text, (params, text)
    assert command(client, FAULT, MOTOR, 4, M.HILMS_FAULT_THRUST_LOSS, 0.25).result == ACCEPTED
    assert _text(client, lambda t: t == "motor 4: thrust_loss 25 % injected") is not None
    assert recv(client, "ATTITUDE") is not None  # the rig kept running


def test_motor_thrust_loss_then_the_loss_of_control_failsafe(rig, client):
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    assert command(client, FAULT, MOTOR, 2, M.HILMS_FAULT_THRUST_LOSS, 1.0).result == ACCEPTED
    assert _text(client, lambda t: t == "motor 2: thrust_loss 100 % injected") is not None
    assert _sys_status(client, lambda h: not h & M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS) is not None
    # no attitude law holds the rig on three motors (docs/how-to/faults.md): loss of control, motors stopped
    severity, lost = _text(client, lambda t: t.startswith("loss of control"))
    assert severity == M.MAV_SEVERITY_CRITICAL and "disarmed" in lost
    hb = recv(client, "HEARTBEAT", condition=lambda m: m.system_status == M.MAV_STATE_EMERGENCY)
    assert not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED
    snap = rig.server.rig.snapshot()
    assert not snap.armed and snap.faults.failsafe and max(snap.voltage_commands) == 0.0
    assert _sys_status(client, lambda h: not h & CONTROL) is not None
    later = _texts_for(client, 0.6)
    assert not any(t.startswith("loss of control") for t in later), later  # once
    assert command(client, FAULT, MOTOR, 2, M.HILMS_FAULT_NONE).result == ACCEPTED
    # the ideal plant tumbles on once the motors stop: the pre-arm checks refuse a plain arm ...
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_DENIED
    assert _text(client, lambda t: t.startswith("Arming denied: ")) is not None
    # ... a forced arm (param2 21196, as PX4 and MAVSDK's arm_force) clears the latch
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1, 21196).result == ACCEPTED
    assert _text(client, lambda t: t == "failsafe cleared (armed again)") is not None
    hb = recv(client, "HEARTBEAT", condition=lambda m: m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
    assert hb.system_status != M.MAV_STATE_EMERGENCY


def test_config_fault_is_announced_at_its_time():
    events = [{"t": 10.0, "sensor": "load_cell", "index": 2, "mode": "dead", "magnitude": 0.0}]
    with RigThread(speedup=8.0, overrides={"faults.events": events}) as rig:
        client = connect(rig.tcp_url)
        try:
            _text(client, lambda t: t == "load cell 2: dead injected")
            assert _text(client, lambda t: t == "load cell 2: readings rejected by the guards")
            cells = recv(client, "HILMS_LOAD_CELLS", condition=lambda m: m.health == 0b1101)
            assert cells is not None and cells.time_usec >= 10_000_000
            assert _sys_status(client, lambda h: not h & M.MAV_SYS_STATUS_SENSOR_GPS) is not None
        finally:
            client.close()


def test_fault_codes_are_the_dialects():
    from rig_emulator.sensors.faults import FAULT_MODES

    assert FAULT_MODES == {name[len("HILMS_FAULT_"):].lower(): code for name, code in vars(M).items()
                           if name.startswith("HILMS_FAULT_") and name != "HILMS_FAULT_ENUM_END"}
