"""AUTOPILOT_VERSION: what the rig is (its MAVLink capabilities and hilms-sil's version).

Kept apart from :mod:`rig_emulator.link.telemetry.status` so that the starting rig's link
(:mod:`rig_emulator.link.boot`) answers it before anything of the rig is imported.
"""

from __future__ import annotations

from importlib import metadata

from protocol.dialect import mavlink as M

CAPABILITIES = (M.MAV_PROTOCOL_CAPABILITY_MISSION_INT | M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | M.MAV_PROTOCOL_CAPABILITY_MAVLINK2 | M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
                | M.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET | M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
                | M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT | M.MAV_PROTOCOL_CAPABILITY_FTP)


def _version_number(text: str) -> int:
    """'1.2.3' -> 0x01020300 (major, minor, patch, FIRMWARE_VERSION_TYPE_DEV = 0)."""
    parts = [int(p) if p.isdigit() else 0 for p in text.split(".")[:3]] + [0, 0, 0]
    return (parts[0] & 0xFF) << 24 | (parts[1] & 0xFF) << 16 | (parts[2] & 0xFF) << 8


def _package_version() -> str:
    try:
        return metadata.version("hilms-sil")
    except metadata.PackageNotFoundError:
        return "0.0.0"


def autopilot_version_message(sysid: int):
    return M.MAVLink_autopilot_version_message(
        capabilities=CAPABILITIES, flight_sw_version=_version_number(_package_version()), middleware_sw_version=0,
        os_sw_version=0, board_version=0, flight_custom_version=[0] * 8, middleware_custom_version=[0] * 8,
        os_custom_version=[0] * 8, vendor_id=0, product_id=0, uid=sysid, uid2=[0] * 18)
