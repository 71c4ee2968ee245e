"""PX4's packing of a flight mode into HEARTBEAT.custom_mode: the main mode in bits 16-23, the sub mode
in bits 24-31 (PX4 ``src/modules/commander/px4_custom_mode.h``). Both sides of the link use it: the rig
to report and enter modes, ground tools to read them."""

from __future__ import annotations


def custom_mode(main: int, sub: int) -> int:
    """HEARTBEAT.custom_mode of PX4 main mode ``main`` and sub mode ``sub``."""
    return (main << 16) | (sub << 24)


def split_custom_mode(value: int) -> tuple[int, int]:
    """(main, sub) PX4 mode of a HEARTBEAT.custom_mode."""
    return (value >> 16) & 0xFF, (value >> 24) & 0xFF


#: the flight modes the rig adds to PX4's (pymavlink's ``px4_map`` does not know them): name -> (main, sub).
#: SYSID is the identification flight, in PX4's first external-mode slot (AUTO, PX4_CUSTOM_SUB_MODE_EXTERNAL1)
#: where PX4 reports a mode an onboard component adds.
RIG_MODES = {"SYSID": (4, 11)}
