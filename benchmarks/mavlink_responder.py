"""The reference vehicle of the MAVLink benchmark: a minimal pymavlink responder.

``python -m benchmarks.mavlink_responder`` listens on ``tcpin:127.0.0.1:0`` (one client),
prints ``responder: serving tcpin:127.0.0.1:PORT`` and answers, with pymavlink's own
``mavutil`` connection and the hilms dialect, as system 1 component 1:

* COMMAND_LONG -> COMMAND_ACK (MAV_RESULT_ACCEPTED) at once;
* the mission upload protocol: MISSION_COUNT -> MISSION_REQUEST_INT for each item in turn ->
  MISSION_ACK (accepted) after the last one; items are stored as received;
* the mission download protocol: MISSION_REQUEST_LIST -> MISSION_COUNT, each
  MISSION_REQUEST_INT -> the stored MISSION_ITEM_INT.

It streams nothing, validates nothing, runs no simulation and has no retry timers: it is the
floor that the benchmark's client code (the same ``MissionClient`` and command loop) can
reach over the same loopback with pymavlink on both ends. SIGTERM stops it.
"""

from __future__ import annotations

import sys

from protocol.dialect import mavlink as M
from protocol.dialect import use_hilms_dialect

PREFIX = "responder: serving "


def _item_reply(msg, target):
    """The stored MISSION_ITEM_INT ``msg`` addressed to ``target`` (sysid, compid)."""
    return M.MAVLink_mission_item_int_message(
        target_system=target[0], target_component=target[1], seq=msg.seq, frame=msg.frame, command=msg.command,
        current=msg.current, autocontinue=msg.autocontinue, param1=msg.param1, param2=msg.param2,
        param3=msg.param3, param4=msg.param4, x=msg.x, y=msg.y, z=msg.z, mission_type=msg.mission_type)


class Responder:
    """The answering logic, apart from the socket (``conn`` is a pymavlink connection)."""

    def __init__(self, conn):
        self.conn = conn
        self.mission: list = []  # stored MISSION_ITEM_INT messages
        self._upload: dict | None = None
        self._count = 0
        self.handled = 0

    def handle(self, m) -> None:
        kind = m.get_type()
        mav = self.conn.mav
        peer = (m.get_srcSystem(), m.get_srcComponent())
        if kind == "COMMAND_LONG":
            mav.command_ack_send(m.command, M.MAV_RESULT_ACCEPTED, 0, 0, peer[0], peer[1])
        elif kind == "MISSION_COUNT":
            self._count = m.count
            self._upload = {}
            if m.count == 0:
                self.mission, self._upload = [], None
                mav.mission_ack_send(peer[0], peer[1], M.MAV_MISSION_ACCEPTED, m.mission_type)
            else:
                mav.mission_request_int_send(peer[0], peer[1], 0, m.mission_type)
        elif kind == "MISSION_ITEM_INT" and self._upload is not None:
            self._upload[m.seq] = m
            if len(self._upload) == self._count:
                self.mission = [self._upload[s] for s in range(self._count)]
                self._upload = None
                mav.mission_ack_send(peer[0], peer[1], M.MAV_MISSION_ACCEPTED, m.mission_type)
            else:
                mav.mission_request_int_send(peer[0], peer[1], m.seq + 1, m.mission_type)
        elif kind == "MISSION_REQUEST_LIST":
            mav.mission_count_send(peer[0], peer[1], len(self.mission), m.mission_type)
        elif kind == "MISSION_REQUEST_INT" and m.seq < len(self.mission):
            mav.send(_item_reply(self.mission[m.seq], peer))
        else:
            return
        self.handled += 1


def main(argv=None) -> int:
    use_hilms_dialect()
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection("tcpin:127.0.0.1:0", source_system=1, source_component=1)
    host, port = conn.listen.getsockname()
    print(f"{PREFIX}tcpin:{host}:{port}", flush=True)
    responder = Responder(conn)
    while True:
        m = conn.recv_match(blocking=True, timeout=1.0)
        if m is not None:
            responder.handle(m)


if __name__ == "__main__":
    sys.exit(main())
