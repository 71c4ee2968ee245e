"""Status messages: HEARTBEAT, SYS_STATUS, EXTENDED_SYS_STATE, SYSTEM_TIME, SERVO_OUTPUT_RAW,
MISSION_CURRENT, and the on-request AUTOPILOT_VERSION. One builder per message, ``(snapshot, ctx) -> message``.

Identity: MAV_TYPE_QUADROTOR, MAV_AUTOPILOT_PX4, component MAV_COMP_ID_AUTOPILOT1: the rig
implements PX4's flight modes and command semantics (:mod:`rig_emulator.link.commands.modes`), so
pymavlink/MAVProxy, MAVSDK and QGroundControl decode its mode and send PX4's commands.
AUTOPILOT_VERSION.flight_sw_version is hilms-sil's own version (QGroundControl's PX4 plugin
shows a "supports PX4 Pro firmware 1.4.1 and above" notice for it; nothing else depends on it).

EXTENDED_SYS_STATE.landed_state: ON_GROUND while disarmed, TAKEOFF while a take-off climbs,
LANDING while a landing descends (land detector on), else IN_AIR.

Faults (docs/how-to/faults.md) map onto SYS_STATUS health bits and HEARTBEAT.system_status from the
snapshot's plain-data :class:`~rig_emulator.simulation.faults.FaultStatus`:

* 3D_GYRO / 3D_ACCEL / 3D_MAG (the fused estimate the rig flies on): unhealthy while the
  supervisor finds that kind's ensemble invalid (majority of modules rejected, or an
  implausible magnitude);
* 3D_GYRO2 / 3D_ACCEL2 / 3D_MAG2 (the module array, its redundancy): unhealthy while any
  module has an injected fault or the ensemble rejects that kind of any module;
* AHRS: unhealthy while the fused gyro or accel is invalid;
* GPS (the rig's virtual position, integrated from the load cells, Eq. 1): unhealthy while
  any load cell has an injected fault or the guards reject its readings (the load-cell
  detail is in HILMS_LOAD_CELLS.health);
* MOTOR_OUTPUTS: unhealthy while any motor has an injected fault, or the failsafe stopped them;
* the control bits: unhealthy once the loss-of-control failsafe has tripped;
* PREARM_CHECK: unhealthy while any of the above is.

HEARTBEAT.system_status: EMERGENCY once the failsafe has tripped or a controller plug-in
failed (until armed again),
CRITICAL while armed with the attitude estimate invalid or the attitude error or body rate
beyond its failsafe limit (before the hold time has passed), else ACTIVE (armed) / STANDBY.
"""

from __future__ import annotations

import time

from protocol.dialect import mavlink
from rig_emulator.control.supervisor import ALERT_ATTITUDE, ALERT_RATE, INVALID_ACCEL, INVALID_GYRO, INVALID_MAG
from rig_emulator.link.telemetry import units as U
from rig_emulator.link.telemetry.power import supply_fields
from rig_emulator.link.telemetry.identity import CAPABILITIES, autopilot_version_message  # noqa: F401 (CAPABILITIES: re-exported)

M = mavlink
GYRO, ACCEL, MAG = M.MAV_SYS_STATUS_SENSOR_3D_GYRO, M.MAV_SYS_STATUS_SENSOR_3D_ACCEL, M.MAV_SYS_STATUS_SENSOR_3D_MAG
GYRO2, ACCEL2, MAG2 = M.MAV_SYS_STATUS_SENSOR_3D_GYRO2, M.MAV_SYS_STATUS_SENSOR_3D_ACCEL2, M.MAV_SYS_STATUS_SENSOR_3D_MAG2
CONTROL_BITS = (M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL | M.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
                | M.MAV_SYS_STATUS_SENSOR_YAW_POSITION | M.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
                | M.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL)
ALWAYS_ON = M.MAV_SYS_STATUS_SENSOR_GPS | M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | M.MAV_SYS_STATUS_AHRS
PRESENT = (GYRO | ACCEL | MAG | GYRO2 | ACCEL2 | MAG2 | ALWAYS_ON | CONTROL_BITS | M.MAV_SYS_STATUS_PREARM_CHECK
           | M.MAV_SYS_STATUS_GEOFENCE)
SENSOR_BITS = GYRO | ACCEL | MAG | GYRO2 | ACCEL2 | MAG2 | ALWAYS_ON
_KINDS = ((GYRO, GYRO2, INVALID_GYRO), (ACCEL, ACCEL2, INVALID_ACCEL), (MAG, MAG2, INVALID_MAG))
def system_status(snap) -> int:
    """MAV_STATE for HEARTBEAT (module doc)."""
    f = snap.faults
    if f is not None and f.failsafe:
        return M.MAV_STATE_EMERGENCY
    if not snap.armed:
        return M.MAV_STATE_STANDBY
    if f is not None and (f.alerts & (ALERT_ATTITUDE | ALERT_RATE) or f.estimate_invalid & (INVALID_GYRO | INVALID_ACCEL)):
        return M.MAV_STATE_CRITICAL
    return M.MAV_STATE_ACTIVE


def heartbeat(snap, ctx):
    base = M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | M.MAV_MODE_FLAG_STABILIZE_ENABLED
    if snap.armed:
        base |= M.MAV_MODE_FLAG_SAFETY_ARMED
    status = system_status(snap)
    if getattr(ctx.rig, "plugin_failure", None) is not None:  # a controller plug-in failed: as the failsafe
        status = M.MAV_STATE_EMERGENCY
    return M.MAVLink_heartbeat_message(
        type=M.MAV_TYPE_QUADROTOR, autopilot=M.MAV_AUTOPILOT_PX4, base_mode=base,
        custom_mode=ctx.modes.custom_mode, system_status=status, mavlink_version=3)


def sensor_health_bits(snap, ctx) -> int:
    """SYS_STATUS health from the snapshot's fault status (mapping in the module doc)."""
    # GEOFENCE health is cleared only while the rig is outside its fence (MAVProxy says "fence breach")
    health = SENSOR_BITS | CONTROL_BITS | M.MAV_SYS_STATUS_GEOFENCE
    if ctx.fence is not None and ctx.fence.breached:
        health &= ~M.MAV_SYS_STATUS_GEOFENCE
    f = snap.faults
    if f is not None:
        imu_injected = any(f.imu_faults)
        for s, (fused, array, invalid) in enumerate(_KINDS):
            if f.estimate_invalid & invalid:
                health &= ~fused
            if imu_injected or f.imu_flagged[s]:
                health &= ~array
        if f.estimate_invalid & (INVALID_GYRO | INVALID_ACCEL):
            health &= ~M.MAV_SYS_STATUS_AHRS
        if any(f.cell_faults) or f.cells_flagged:
            health &= ~M.MAV_SYS_STATUS_SENSOR_GPS
        if any(f.motor_faults) or (f.failsafe and f.failsafe_action == "disarm"):
            health &= ~M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
        if f.failsafe:
            health &= ~CONTROL_BITS
    if health & (SENSOR_BITS | CONTROL_BITS) == SENSOR_BITS | CONTROL_BITS:
        health |= M.MAV_SYS_STATUS_PREARM_CHECK
    return health


def sys_status(snap, ctx):
    enabled = PRESENT if snap.armed else PRESENT & ~CONTROL_BITS
    if ctx.cfg["fence.enabled"]:
        enabled |= M.MAV_SYS_STATUS_GEOFENCE
    dropped = sum(ctx.counters.dropped.values())
    total = ctx.counters.received + dropped
    return M.MAVLink_sys_status_message(
        onboard_control_sensors_present=PRESENT, onboard_control_sensors_enabled=enabled,
        onboard_control_sensors_health=sensor_health_bits(snap, ctx), load=U.clamp_int(ctx.load_fraction * 1000.0, 0, 1000),
        **supply_fields(snap, ctx),  # the bench supply (telemetry_power.py)
        battery_remaining=-1, drop_rate_comm=U.clamp_int(10000.0 * dropped / total, 0, 10000) if total else 0,
        errors_comm=dropped % 65536, errors_count1=0, errors_count2=0, errors_count3=0, errors_count4=0,
        onboard_control_sensors_present_extended=0, onboard_control_sensors_enabled_extended=0,
        onboard_control_sensors_health_extended=0)


def extended_sys_state(snap, ctx):
    landed = M.MAV_LANDED_STATE_IN_AIR if snap.armed else M.MAV_LANDED_STATE_ON_GROUND
    tasks = ctx.flight.tasks if ctx.flight is not None else None
    if snap.armed and tasks is not None:
        if tasks.landing:
            landed = M.MAV_LANDED_STATE_LANDING
        elif tasks.task == "takeoff":
            landed = M.MAV_LANDED_STATE_TAKEOFF
    return M.MAVLink_extended_sys_state_message(vtol_state=M.MAV_VTOL_STATE_UNDEFINED, landed_state=landed)


def mission_current(snap, ctx):
    """MISSION_CURRENT of the mission executor (seq, total, mission_state, mission_mode)."""
    return ctx.mission.current_message()


def system_time(snap, ctx):
    return M.MAVLink_system_time_message(time_unix_usec=U.unix_usec(time.time()), time_boot_ms=U.time_boot_ms(snap.stamp_us))


SERVO_FIELDS = tuple(f"servo{i + 1}_raw" for i in range(16))


def servo_output_raw(snap, ctx):
    v_max = ctx.cfg["motors.voltage_max"]
    pwm = [U.pwm_us(v, v_max) for v in snap.voltage_commands] + [0] * 12
    return M.MAVLink_servo_output_raw_message(time_usec=U.time_usec_u32(snap.commands_stamp_us), port=0,
                                              **dict(zip(SERVO_FIELDS, pwm)))


def autopilot_version(snap, ctx):
    return autopilot_version_message(ctx.sysid)  # rig_emulator.link.telemetry.identity
