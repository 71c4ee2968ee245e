"""UDP: the frames of one tick packed into few datagrams, every frame whole and parsable."""

import socket
import time

from protocol.dialect import mavlink as M
from rig_emulator.link.endpoints.sockets import MAX_DATAGRAM_BYTES, open_endpoint
from rig_emulator.testing.rig import RigThread, stamp_s


def _frame(mav, i: int) -> bytes:
    msg = M.MAVLink_statustext_message(severity=6, text=f"frame {i:03d} ".encode() * 4, id=0, chunk_seq=0)
    return bytes(msg.pack(mav))


def test_frames_are_packed_up_to_the_datagram_limit():
    ep = open_endpoint("udpin:127.0.0.1:0")
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.settimeout(5.0)
    try:
        client.sendto(b"hello", ep.local_address)
        deadline = time.monotonic() + 5
        events = []
        while not events and time.monotonic() < deadline:
            events = [e for e in ep.poll() if e[0] == "open"]
        key = events[0][1]
        mav = M.MAVLink(None, srcSystem=1, srcComponent=1)
        frames = [_frame(mav, i) for i in range(40)]
        for f in frames:
            assert ep.send(key, f)
        ep.flush()
        got = []
        while sum(len(d) for d in got) < sum(len(f) for f in frames):
            got.append(client.recvfrom(65536)[0])
        per = (MAX_DATAGRAM_BYTES // len(frames[0]))
        assert len(got) == -(-len(frames) // per) and all(len(d) <= MAX_DATAGRAM_BYTES for d in got)
        assert b"".join(got) == b"".join(frames)  # in order, nothing lost, no frame split
        assert ep.datagrams_sent == len(got) and ep.frames_sent == len(frames) and ep.tx_dropped == 0
    finally:
        client.close()
        ep.close()


def test_served_rig_at_max_speed_packs_its_telemetry_and_keeps_its_rates():
    """``--speedup max``: several frames a datagram, each frame parses, ATTITUDE at its 25 Hz of
    simulated time (the telemetry is built per simulated chunk however the ticks fall)."""
    with RigThread(speedup=0, extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        url = next(u for u in rig.urls if u.startswith("udpin:"))
        _, host, port = url.split(":")
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.settimeout(5.0)
        tx = M.MAVLink(None, srcSystem=255, srcComponent=190)
        rx = M.MAVLink(None, srcSystem=255, srcComponent=190)
        rx.robust_parsing = True
        sock.sendto(M.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3).pack(tx), (host, int(port)))
        sizes, stamps, bad, frames = [], [], 0, 0
        try:
            while len(stamps) < 200:
                data = sock.recvfrom(65536)[0]
                sizes.append(len(data))
                for msg in rx.parse_buffer(data) or []:
                    if msg.get_type() == "BAD_DATA":
                        bad += 1
                        continue
                    frames += 1
                    if msg.get_type() == "ATTITUDE":
                        stamps.append(stamp_s(msg))
                assert rx.buf_len() == 0  # no frame spans two datagrams
        finally:
            sock.close()
        assert bad == 0 and max(sizes) <= MAX_DATAGRAM_BYTES
        assert frames > 2 * len(sizes), (frames, len(sizes))  # packed: one datagram per frame before
        span = stamps[-1] - stamps[0]
        assert abs((len(stamps) - 1) - 25.0 * span) <= 2, (len(stamps), span)
