"""A starting rig speaks at once: HEARTBEAT with MAV_STATE_BOOT while its step loop
compiles, commands refused with TEMPORARILY_REJECTED and a reason, then STANDBY on the same link.

The compile is stood in for by the documented seam ``HILMS_SERVE_BOOT_DELAY_S`` (the rig waits
that long before building itself; a cold numba cache takes minutes, too much for the suite).
"""

import time

from protocol.dialect import mavlink as M
from rig_emulator.link.boot import BOOT_TEXT
from rig_emulator.testing.rig import RigProcess, command, connect, recv, udp_listener

BOOT_DELAY_S = 12.0


def test_boot_heartbeat_while_compiling_then_standby():
    listener, udp_url = udp_listener()
    t0 = time.monotonic()
    rig = RigProcess(speedup=1, extra_endpoints=[udp_url], wait_ready=False,
                     env={"HILMS_SERVE_BOOT_DELAY_S": str(BOOT_DELAY_S)})
    try:
        hb = recv(listener, "HEARTBEAT", BOOT_DELAY_S)
        first_s = time.monotonic() - t0
        assert hb is not None and hb.system_status == M.MAV_STATE_BOOT, hb
        assert not rig.ready  # heard while the rig was still being built
        assert (hb.type, hb.autopilot) == (M.MAV_TYPE_QUADROTOR, M.MAV_AUTOPILOT_PX4)
        assert not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED
        print(f"first BOOT heartbeat {first_s:.2f} s after start")

        conn = connect(rig.tcp_url)
        assert recv(conn, "HEARTBEAT", 5, lambda m: m.system_status == M.MAV_STATE_BOOT) is not None
        ack = command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        assert ack.result == M.MAV_RESULT_TEMPORARILY_REJECTED
        text = recv(conn, "STATUSTEXT", 5)
        assert text is not None and text.text == BOOT_TEXT
        ack = command(conn, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
        assert ack.result == M.MAV_RESULT_ACCEPTED
        version = recv(conn, "AUTOPILOT_VERSION", 5)
        assert version is not None and version.capabilities & M.MAV_PROTOCOL_CAPABILITY_MAVLINK2

        # the same connections carry the running rig's HEARTBEAT (STANDBY) and answers
        hb = recv(conn, "HEARTBEAT", 240, lambda m: m.system_status != M.MAV_STATE_BOOT)
        assert hb is not None and hb.system_status == M.MAV_STATE_STANDBY
        assert recv(listener, "HEARTBEAT", 10, lambda m: m.system_status == M.MAV_STATE_STANDBY) is not None
        rig.wait_ready(30)
        assert command(conn, M.MAV_CMD_GET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE).result == M.MAV_RESULT_ACCEPTED
        assert recv(conn, "ATTITUDE", 10) is not None
        conn.close()
    finally:
        code = rig.stop()
        listener.close()
    assert code == 0
    assert any(line.startswith("rig-emulator: ready") and "1 commands were refused" in line for line in rig.output)
