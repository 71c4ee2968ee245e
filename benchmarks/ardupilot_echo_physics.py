"""The reference of the ardupilot-json benchmark: a JSON physics that does nothing but answer.

``python -m benchmarks.ardupilot_echo_physics`` binds UDP ``127.0.0.1:0``, prints
``echo-physics: serving udp:127.0.0.1:PORT`` and answers every ArduPilot servo packet, to the
address it came from, with a JSON line of the rig's shape and constant contents (a vehicle at
rest), its ``timestamp`` 1 ms later for each new frame. No physics, no sensors, no ground link:
the floor that a flight stack (here the stand-in of ``gcs_tools/ardupilot_peer.py``) and
loopback UDP reach. SIGTERM stops it.
"""

from __future__ import annotations

import socket
import struct
import sys

PREFIX = "echo-physics: serving "
STEP_S = 0.001
_LINE = ('\n{"timestamp":%r,"imu":{"gyro":[0.0,0.0,0.0],"accel_body":[0.0,0.0,-9.80665]},'
         '"position":[0.0,0.0,-0.0],"velocity":[0.0,0.0,-0.0],"quaternion":[1.0,0.0,0.0,0.0]}\n')


def serve() -> int:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    print(f"{PREFIX}udp:127.0.0.1:{sock.getsockname()[1]}", flush=True)
    last, steps, reply = -1, 0, b""
    while True:
        data, addr = sock.recvfrom(2048)
        if len(data) < 8:
            continue
        count = struct.unpack_from("<I", data, 4)[0]
        if count != last:
            if count < last:
                steps = 0
            last, steps = count, steps + 1
            reply = (_LINE % (steps * STEP_S)).encode("ascii")
        sock.sendto(reply, addr)


if __name__ == "__main__":
    sys.exit(serve())
