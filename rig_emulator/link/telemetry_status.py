"""Status messages: HEARTBEAT, SYS_STATUS, EXTENDED_SYS_STATE, SYSTEM_TIME, SERVO_OUTPUT_RAW,
MISSION_CURRENT, and the on-request AUTOPILOT_VERSION. One builder per message, ``(snapshot, ctx) -> message``.

Identity: MAV_TYPE_QUADROTOR, MAV_AUTOPILOT_GENERIC, component MAV_COMP_ID_AUTOPILOT1; the
flight mode is reported in PX4's custom-mode layout (:mod:`rig_emulator.link.modes`).
"""

from __future__ import annotations

import time
from importlib import metadata

from protocol.dialect import mavlink
from rig_emulator.link import mavlink_units as U

M = mavlink
GYRO, ACCEL, MAG = M.MAV_SYS_STATUS_SENSOR_3D_GYRO, M.MAV_SYS_STATUS_SENSOR_3D_ACCEL, M.MAV_SYS_STATUS_SENSOR_3D_MAG
GYRO2, ACCEL2, MAG2 = M.MAV_SYS_STATUS_SENSOR_3D_GYRO2, M.MAV_SYS_STATUS_SENSOR_3D_ACCEL2, M.MAV_SYS_STATUS_SENSOR_3D_MAG2
CONTROL_BITS = (M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL | M.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
                | M.MAV_SYS_STATUS_SENSOR_YAW_POSITION | M.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
                | M.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL)
ALWAYS_ON = M.MAV_SYS_STATUS_SENSOR_GPS | M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | M.MAV_SYS_STATUS_AHRS
PRESENT = GYRO | ACCEL | MAG | GYRO2 | ACCEL2 | MAG2 | ALWAYS_ON | CONTROL_BITS | M.MAV_SYS_STATUS_PREARM_CHECK
CAPABILITIES = (M.MAV_PROTOCOL_CAPABILITY_MISSION_INT | M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | M.MAV_PROTOCOL_CAPABILITY_MAVLINK2 | M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
                | M.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET | M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED)


def _version_number(text: str) -> int:
    """'1.2.3' -> 0x01020300 (major, minor, patch, FIRMWARE_VERSION_TYPE_DEV = 0)."""
    parts = [int(p) if p.isdigit() else 0 for p in text.split(".")[:3]] + [0, 0, 0]
    return (parts[0] & 0xFF) << 24 | (parts[1] & 0xFF) << 16 | (parts[2] & 0xFF) << 8


def _package_version() -> str:
    try:
        return metadata.version("hilms-sil")
    except metadata.PackageNotFoundError:
        return "0.0.0"


def heartbeat(snap, ctx):
    base = M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | M.MAV_MODE_FLAG_STABILIZE_ENABLED
    if snap.armed:
        base |= M.MAV_MODE_FLAG_SAFETY_ARMED
    return M.MAVLink_heartbeat_message(
        type=M.MAV_TYPE_QUADROTOR, autopilot=M.MAV_AUTOPILOT_GENERIC, base_mode=base,
        custom_mode=ctx.modes.custom_mode, system_status=M.MAV_STATE_ACTIVE if snap.armed else M.MAV_STATE_STANDBY,
        mavlink_version=3)


def sensor_health_bits(snap, ctx) -> int:
    """SYS_STATUS health: a sensor bit is healthy while every module's device of that kind is."""
    r = ctx.readings(snap)
    imu_ok = all(r.imu_healthy)
    # The rig has no geofence, so none can be breached: ground stations such as MAVProxy read a
    # cleared GEOFENCE health bit as "fence breach" whether or not the fence is present.
    health = ALWAYS_ON | CONTROL_BITS | M.MAV_SYS_STATUS_GEOFENCE
    if imu_ok:
        health |= GYRO | ACCEL | MAG | GYRO2 | ACCEL2 | MAG2
    if imu_ok and all(r.load_healthy):
        health |= M.MAV_SYS_STATUS_PREARM_CHECK
    return health


def sys_status(snap, ctx):
    enabled = PRESENT if snap.armed else PRESENT & ~CONTROL_BITS
    dropped = sum(ctx.counters.dropped.values())
    total = ctx.counters.received + dropped
    return M.MAVLink_sys_status_message(
        onboard_control_sensors_present=PRESENT, onboard_control_sensors_enabled=enabled,
        onboard_control_sensors_health=sensor_health_bits(snap, ctx), load=U.clamp_int(ctx.load_fraction * 1000.0, 0, 1000),
        voltage_battery=U.clamp_int(ctx.cfg["motors.voltage_max"] * 1000.0, 0, 65534), current_battery=-1,
        battery_remaining=-1, drop_rate_comm=U.clamp_int(10000.0 * dropped / total, 0, 10000) if total else 0,
        errors_comm=dropped % 65536, errors_count1=0, errors_count2=0, errors_count3=0, errors_count4=0,
        onboard_control_sensors_present_extended=0, onboard_control_sensors_enabled_extended=0,
        onboard_control_sensors_health_extended=0)


def extended_sys_state(snap, ctx):
    landed = M.MAV_LANDED_STATE_IN_AIR if snap.armed else M.MAV_LANDED_STATE_ON_GROUND
    return M.MAVLink_extended_sys_state_message(vtol_state=M.MAV_VTOL_STATE_UNDEFINED, landed_state=landed)


def mission_current(snap, ctx):
    """MISSION_CURRENT of the mission executor (seq, total, mission_state, mission_mode)."""
    return ctx.mission.current_message()


def system_time(snap, ctx):
    return M.MAVLink_system_time_message(time_unix_usec=U.unix_usec(time.time()), time_boot_ms=U.time_boot_ms(snap.time_s))


def servo_output_raw(snap, ctx):
    v_max = ctx.cfg["motors.voltage_max"]
    pwm = [U.pwm_us(v, v_max) for v in snap.voltage_commands] + [0] * 12
    return M.MAVLink_servo_output_raw_message(time_usec=U.time_usec_u32(snap.time_s), port=0, **{
        f"servo{i + 1}_raw": pwm[i] for i in range(16)})


def autopilot_version(snap, ctx):
    version = _version_number(_package_version())
    return M.MAVLink_autopilot_version_message(
        capabilities=CAPABILITIES, flight_sw_version=version, middleware_sw_version=0, os_sw_version=0,
        board_version=0, flight_custom_version=[0] * 8, middleware_custom_version=[0] * 8,
        os_custom_version=[0] * 8, vendor_id=0, product_id=0, uid=ctx.sysid, uid2=[0] * 18)
