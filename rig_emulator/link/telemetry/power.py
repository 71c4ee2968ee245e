"""The bench supply in telemetry: SYS_STATUS's battery fields and BATTERY_STATUS.

The rig runs from a 0..15 V bench supply (Fig. 11), not a battery: the voltage is the
supply's, the current what the four motor drivers draw now (:mod:`rig_emulator.physics.electrical`
through :meth:`LiveRig.power`), the consumed charge and energy what it delivered since the
rig started. There is no capacity, so the remaining charge is unknown (-1) and the battery
type MAV_BATTERY_TYPE_UNKNOWN; the charge state stays OK.
"""

from __future__ import annotations

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry import units as U

UINT16_UNUSED = 65535


def supply_fields(snap, ctx) -> dict:
    """SYS_STATUS voltage_battery (mV) and current_battery (cA) of the bench supply at ``snap``."""
    p = ctx.rig.power(snap)
    return {"voltage_battery": U.clamp_int(p.voltage_v * 1000.0, 0, 65534, 65535),
            "current_battery": U.clamp_int(p.current_a * 100.0, 0, 32767, -1)}


def battery_status(snap, ctx):
    p = ctx.rig.power(snap)
    voltages = [U.clamp_int(p.voltage_v * 1000.0, 0, 65534, UINT16_UNUSED)] + [UINT16_UNUSED] * 9
    return M.MAVLink_battery_status_message(
        id=0, battery_function=M.MAV_BATTERY_FUNCTION_ALL, type=M.MAV_BATTERY_TYPE_UNKNOWN,
        temperature=32767, voltages=voltages, current_battery=U.clamp_int(p.current_a * 100.0, 0, 32767, -1),
        current_consumed=U.clamp_int(p.charge_c / 3.6, 0, 2**31 - 1, -1),  # C -> mAh
        energy_consumed=U.clamp_int(p.energy_j / 100.0, 0, 2**31 - 1, -1),  # J -> hJ
        battery_remaining=-1, time_remaining=0, charge_state=M.MAV_BATTERY_CHARGE_STATE_OK,
        voltages_ext=[0, 0, 0, 0], mode=M.MAV_BATTERY_MODE_UNKNOWN, fault_bitmask=0)
