"""Several ground stations at once: TCP and UDP peers each get telemetry and can command."""

from protocol.dialect import mavlink as M
from rig_emulator.testing.rig import RigThread, command, connect, recv, udp_listener


def test_tcp_and_udp_clients_together():
    udp_client, udp_url = udp_listener()
    with RigThread(speedup=4.0, extra_endpoints=[udp_url, "udpin:127.0.0.1:0"]) as rig:
        tcp_a = connect(rig.tcp_url)
        tcp_b = connect(rig.tcp_url, source_system=254)
        udpin_url = next(u for u in rig.urls if u.startswith("udpin:"))
        udp_c = connect(udpin_url, source_system=253)
        udp_c.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)  # makes the rig see this peer
        clients = [tcp_a, tcp_b, udp_client, udp_c]
        for c in clients:
            assert recv(c, "ATTITUDE") is not None
        for i, c in enumerate(clients):
            ack = command(c, M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
            assert ack is not None and ack.result == M.MAV_RESULT_ACCEPTED, i
        assert command(udp_client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        for c in (tcp_a, tcp_b, udp_c):  # the change reaches every peer
            hb = recv(c, "HEARTBEAT", condition=lambda m: m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
            assert hb is not None
        udp_client.mav.param_set_send(1, 1, b"WP_RADIUS", 0.2, M.MAV_PARAM_TYPE_REAL32)
        for c in clients:  # accepted parameter changes are echoed to every peer
            m = recv(c, "PARAM_VALUE", condition=lambda m: m.param_id == "WP_RADIUS")
            assert m is not None and abs(m.param_value - 0.2) < 1e-6
        tcp_b.close()
        assert command(tcp_a, 31999).result == M.MAV_RESULT_UNSUPPORTED  # a client leaving disturbs nobody
        for c in (tcp_a, udp_client, udp_c):
            c.close()
