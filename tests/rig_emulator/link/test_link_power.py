"""The bench supply in telemetry (pymavlink): SYS_STATUS and BATTERY_STATUS carry the supply's
voltage and the current the motors draw (physics/electrical.py), not a constant."""

from protocol.dialect import mavlink as M
from rig_emulator.testing.rig import RigThread, command, connect, recv
from rig_emulator.physics.electrical import supply_current


def test_supply_current_follows_the_motors():
    with RigThread(speedup=8.0) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        idle = recv(conn, "SYS_STATUS", 5.0)
        assert idle.voltage_battery == 15000 and idle.current_battery == 0  # disarmed: motors at 0 V
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        for _ in range(6):  # a few seconds of hovering on the ground... then the current of the hover thrust
            recv(conn, "HEARTBEAT", 5.0)
        hover = recv(conn, "SYS_STATUS", 5.0)
        snap = rig.server.rig.snapshot()
        want = supply_current(snap.thrusts, snap.voltage_commands, 15.0, 0.016)
        assert 1500 < hover.current_battery < 3000, hover  # ~21 A for 21.9 N of thrust
        assert abs(hover.current_battery - 100 * want) < 300
        battery = recv(conn, "BATTERY_STATUS", 5.0)
        assert battery.voltages[0] == 15000 and battery.current_battery > 1500 and battery.current_consumed > 0
        assert battery.battery_remaining == -1  # a bench supply: no capacity
        conn.close()
