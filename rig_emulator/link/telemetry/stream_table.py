"""Every message the rig can stream: its builder, default rate and legacy stream group.

Default rates (Hz of simulated time) are sized like a ground-station link (about 170
messages/s in all). MAV_CMD_SET_MESSAGE_INTERVAL changes one message on the requesting
peer; the legacy REQUEST_DATA_STREAM changes a whole MAV_DATA_STREAM group. HEARTBEAT is
not in this table: it goes out at 1 Hz of wall-clock time (see the server).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry import attitude as A
from rig_emulator.link.telemetry import position as P
from rig_emulator.link.telemetry import sensors as S
from rig_emulator.link.telemetry import status as T
from rig_emulator.link.ftp.component_metadata import component_information_message, component_metadata_message
from rig_emulator.link.telemetry.link_status import link_status
from rig_emulator.link.telemetry.power import battery_status
from rig_emulator.link.commands.standard_modes import current_mode
from rig_emulator.link.commands.standard_modes import monitor as modes_monitor


@dataclass(frozen=True)
class Stream:
    name: str
    msg_id: int
    default_hz: float
    build: Callable  # (snapshot, ctx) -> message or list of messages
    group: int  # MAV_DATA_STREAM_*


def _s(cls, hz, build, group) -> Stream:
    return Stream(cls.msgname, cls.id, hz, build, group)


STREAMS: dict[int, Stream] = {s.msg_id: s for s in (
    _s(M.MAVLink_sys_status_message, 2.0, T.sys_status, M.MAV_DATA_STREAM_EXTENDED_STATUS),
    _s(M.MAVLink_extended_sys_state_message, 1.0, T.extended_sys_state, M.MAV_DATA_STREAM_EXTENDED_STATUS),
    _s(M.MAVLink_gps_raw_int_message, 2.0, P.gps_raw_int, M.MAV_DATA_STREAM_EXTENDED_STATUS),
    _s(M.MAVLink_mission_current_message, 1.0, T.mission_current, M.MAV_DATA_STREAM_EXTENDED_STATUS),
    _s(M.MAVLink_battery_status_message, 1.0, battery_status, M.MAV_DATA_STREAM_EXTENDED_STATUS),
    _s(M.MAVLink_system_time_message, 1.0, T.system_time, M.MAV_DATA_STREAM_EXTRA3),
    _s(M.MAVLink_home_position_message, 0.5, P.home_position, M.MAV_DATA_STREAM_EXTRA3),
    _s(M.MAVLink_attitude_message, 25.0, A.attitude, M.MAV_DATA_STREAM_EXTRA1),
    _s(M.MAVLink_attitude_quaternion_message, 10.0, A.attitude_quaternion, M.MAV_DATA_STREAM_EXTRA1),
    _s(M.MAVLink_sim_state_message, 5.0, P.sim_state, M.MAV_DATA_STREAM_EXTRA1),
    _s(M.MAVLink_vfr_hud_message, 4.0, P.vfr_hud, M.MAV_DATA_STREAM_EXTRA2),
    _s(M.MAVLink_attitude_target_message, 10.0, A.attitude_target, M.MAV_DATA_STREAM_RAW_CONTROLLER),
    _s(M.MAVLink_position_target_local_ned_message, 5.0, P.position_target_local_ned, M.MAV_DATA_STREAM_RAW_CONTROLLER),
    _s(M.MAVLink_hilms_controller_state_message, 10.0, A.hilms_controller_state, M.MAV_DATA_STREAM_RAW_CONTROLLER),
    _s(M.MAVLink_local_position_ned_message, 10.0, P.local_position_ned, M.MAV_DATA_STREAM_POSITION),
    _s(M.MAVLink_global_position_int_message, 5.0, P.global_position_int, M.MAV_DATA_STREAM_POSITION),
    _s(M.MAVLink_servo_output_raw_message, 5.0, T.servo_output_raw, M.MAV_DATA_STREAM_RC_CHANNELS),
    _s(M.MAVLink_highres_imu_message, 10.0, S.highres_imu, M.MAV_DATA_STREAM_RAW_SENSORS),
    _s(M.MAVLink_scaled_imu_message, 5.0, S.scaled_imu, M.MAV_DATA_STREAM_RAW_SENSORS),
    _s(M.MAVLink_scaled_imu2_message, 5.0, S.scaled_imu2, M.MAV_DATA_STREAM_RAW_SENSORS),
    _s(M.MAVLink_scaled_imu3_message, 5.0, S.scaled_imu3, M.MAV_DATA_STREAM_RAW_SENSORS),
    _s(M.MAVLink_hilms_imu_module_message, 2.0, S.hilms_imu_module, M.MAV_DATA_STREAM_RAW_SENSORS),
    _s(M.MAVLink_hilms_load_cells_message, 10.0, S.hilms_load_cells, M.MAV_DATA_STREAM_RAW_SENSORS),
    _s(M.MAVLink_named_value_float_message, 2.0, S.named_value_float, M.MAV_DATA_STREAM_RAW_SENSORS),
)}

#: Messages a client may ask for once with MAV_CMD_REQUEST_MESSAGE besides the streams.
ON_REQUEST: dict[int, Callable] = {
    M.MAVLINK_MSG_ID_HEARTBEAT: T.heartbeat,
    M.MAVLINK_MSG_ID_AUTOPILOT_VERSION: T.autopilot_version,
    M.MAVLINK_MSG_ID_NAMED_VALUE_INT: link_status,  # the link and loop counters (rig_emulator.link.telemetry.link_status)
    M.MAVLINK_MSG_ID_COMPONENT_METADATA: component_metadata_message,  # where the metadata files are (MAVFTP)
    M.MAVLINK_MSG_ID_COMPONENT_INFORMATION: component_information_message,
    M.MAVLINK_MSG_ID_FENCE_STATUS: lambda snap, ctx: ctx.fence.status_message(),
    # standard modes (rig_emulator.link.commands.standard_modes; AVAILABLE_MODES itself takes an index: commands.py)
    M.MAVLINK_MSG_ID_CURRENT_MODE: lambda snap, ctx: current_mode(ctx.modes),
    M.MAVLINK_MSG_ID_AVAILABLE_MODES_MONITOR: lambda snap, ctx: modes_monitor(),
    **{msg_id: s.build for msg_id, s in STREAMS.items()},
}


def default_rates() -> dict[int, float]:
    return {msg_id: s.default_hz for msg_id, s in STREAMS.items()}


def group_members(group: int) -> list[int]:
    """Message ids of a MAV_DATA_STREAM group (MAV_DATA_STREAM_ALL: every stream)."""
    if group == M.MAV_DATA_STREAM_ALL:
        return list(STREAMS)
    return [msg_id for msg_id, s in STREAMS.items() if s.group == group]
