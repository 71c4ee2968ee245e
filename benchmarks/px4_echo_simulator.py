"""The reference of the px4-lockstep benchmark: a simulator that does nothing but answer.

``python -m benchmarks.px4_echo_simulator`` listens on ``127.0.0.1:0`` (TCP, one flight
stack), prints ``echo-simulator: serving tcpin:127.0.0.1:PORT`` and speaks the Simulator
MAVLink API with pymavlink's common dialect: it sends a first HIL_SENSOR at once, then
answers every HIL_ACTUATOR_CONTROLS with the next step's messages, the same ones the rig
sends (HIL_SENSOR every 4 ms of simulated time, HIL_STATE_QUATERNION every step, HIL_GPS
every 25th step), with constant contents (a vehicle at rest). No physics, no sensors, no
ground link: it is the floor that a flight stack (here the pymavlink stand-in of
``gcs_tools/px4_peer.py``) and loopback TCP reach. SIGTERM stops it.
"""

from __future__ import annotations

import socket
import sys

from pymavlink.dialects.v20 import common as mavlink

PREFIX = "echo-simulator: serving "
STEP_US = 4000
GPS_DIV = 25


def _messages(step: int):
    t = step * STEP_US
    out = [mavlink.MAVLink_hil_sensor_message(t, 0.0, 0.0, -9.81, 0.0, 0.0, 0.0, 0.2, 0.03, 0.35, 877.0, 0.0,
                                               1200.0, 7.2, 0x1FFF, 0),
           mavlink.MAVLink_hil_state_quaternion_message(t, [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0, 357000000,
                                                        514000000, 1200000, 0, 0, 0, 0, 0, 0, 0, -1000)]
    if step % GPS_DIV == 0:
        out.append(mavlink.MAVLink_hil_gps_message(t, 3, 357000000, 514000000, 1200000, 30, 30, 0, 0, 0, 0, 65535,
                                                   10, 0, 0))
    return out


def serve() -> int:
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    print(f"{PREFIX}tcpin:127.0.0.1:{listener.getsockname()[1]}", flush=True)
    while True:
        sock, _ = listener.accept()
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        step = 1
        sock.sendall(b"".join(m.pack(mav) for m in _messages(step)))
        while True:
            try:
                data = sock.recv(65536)
            except ConnectionResetError:  # the client closed with our last step unread
                break
            if not data:
                break
            for msg in mav.parse_buffer(data) or ():
                if msg.get_type() == "HIL_ACTUATOR_CONTROLS":
                    step += 1
                    sock.sendall(b"".join(m.pack(mav) for m in _messages(step)))
        sock.close()


if __name__ == "__main__":
    sys.exit(serve())
