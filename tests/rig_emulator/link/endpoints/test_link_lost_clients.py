"""A TCP ground station that vanishes (reset, broken pipe) while the rig is sending to it is
forgotten: its channel closes, and nothing more is queued for it or counted as dropped."""

from __future__ import annotations

import socket
import struct

from rig_emulator.link.endpoints.sockets import open_endpoint

BOUND = 1000  # loop bound, not a measure: the reset arrives within a few sends on the loopback


def _reset(sock: socket.socket) -> None:
    """Close with a reset (SO_LINGER 0), as a killed ground station's host does."""
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    sock.close()


def test_a_client_a_flush_finds_broken_is_reported_closed():
    ep = open_endpoint("tcpin:127.0.0.1:0")
    client = socket.create_connection(ep.local_address, timeout=10)
    try:
        key = None
        for _ in range(BOUND):
            opened = [k for event, k, _ in ep.poll() if event == "open"]
            if opened:
                key = opened[0]
                break
        assert key is not None
        _reset(client)
        for _ in range(BOUND):  # the rig sends before it reads again: the flush meets the reset
            ep.send(key, b"\xfd" + bytes(40))
            ep.flush()
            if key not in ep.clients:
                break
        assert key not in ep.clients
        events = ep.poll()
        assert ("closed", key, b"") in events
        assert ("closed", key, b"") not in ep.poll()  # once
    finally:
        ep.close()
