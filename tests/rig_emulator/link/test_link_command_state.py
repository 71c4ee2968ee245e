"""A command sees the state the command before it left, with no simulation step in between: the
server's per-chunk snapshot cache is dropped after every command (a calibration sent right after an
accepted arm was once answered TEMPORARILY_REJECTED, as if disarmed, when the rig's loop had not
stepped between the two: seen under stress-ng in tests/rig_emulator/link/commands)."""

from protocol.dialect import mavlink as M
from rig_emulator.config.loader import load_config
from rig_emulator.link.serve import prepare_rig
from rig_emulator.link.server import RigServer
from rig_emulator.testing.rig import capture_channel


def test_a_command_right_after_arming_sees_the_rig_armed():
    server = RigServer(prepare_rig(load_config()), [], speedup=1.0)
    try:
        channel, sent = capture_channel(server)
        for _ in range(20):  # the estimate settles, as a served rig's does before anyone arms it
            server.step_chunk()

        def ack(command, *params):
            sent.clear()
            server.handle(M.MAVLink_command_long_message(server.sysid, 1, command, 0, *params), channel)
            return [m.result for m in sent if m.get_type() == "COMMAND_ACK"]

        assert server.snapshot().armed is False  # cached for this chunk, as the telemetry caches it
        assert ack(M.MAV_CMD_COMPONENT_ARM_DISARM, 1, 0, 0, 0, 0, 0, 0) == [M.MAV_RESULT_ACCEPTED]
        assert server.snapshot().armed is True
        # within the calibration rate limit and in the same chunk: refused because armed
        assert ack(M.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 1, 0, 0) == [M.MAV_RESULT_DENIED]
    finally:
        server.close()
