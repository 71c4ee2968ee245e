"""The link while the rig starts: HEARTBEAT (MAV_STATE_BOOT) from the first second, before the
step loop is compiled.

A cold numba cache compiles the step loop for minutes; ground stations give up on a vehicle
that says nothing for 15-20 s (MAVSDK, MAVProxy). ``rig-emulator serve`` therefore opens its
endpoints first and hands them to a :class:`BootLink`, a thread that speaks for the rig while
the main thread imports, builds and compiles it:

* HEARTBEAT at 1 Hz of wall time, ``system_status`` MAV_STATE_BOOT (the rig's identity:
  quadrotor, PX4 modes, disarmed in POSCTL, as once it runs);
* every new peer gets STATUSTEXT "starting: compiling the step loop" (NOTICE), repeated every
  :data:`NOTICE_PERIOD_S`;
* COMMAND_LONG / COMMAND_INT: AUTOPILOT_VERSION requests (REQUEST_MESSAGE 148,
  REQUEST_AUTOPILOT_CAPABILITIES) are answered; every other command gets COMMAND_ACK
  MAV_RESULT_TEMPORARILY_REJECTED and the STATUSTEXT, so a client retries later;
* other messages (parameter and mission requests, set-points) are not answered yet: their
  protocols retry, and the rig answers them once it runs.

When the rig is ready, :meth:`BootLink.hand_over` stops the thread and returns the endpoints
with the peers heard meanwhile; the :class:`~rig_emulator.link.server.RigServer` adopts them
(same sockets, same ports, the same TCP connections) and its first HEARTBEAT says
MAV_STATE_STANDBY. Nothing here imports the rig: the thread runs from the first second.
"""

from __future__ import annotations

import select
import threading
import time

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry.identity import autopilot_version_message

HEARTBEAT_PERIOD_S = 1.0
NOTICE_PERIOD_S = 10.0
BOOT_TEXT = "starting: compiling the step loop"
POSCTL_CUSTOM_MODE = 3 << 16  # PX4 main mode POSCTL: the mode the rig starts in (commands/modes.py)
COMPID = M.MAV_COMP_ID_AUTOPILOT1
_AUTOPILOT_VERSION_REQUESTS = (M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,)


def boot_heartbeat():
    return M.MAVLink_heartbeat_message(
        type=M.MAV_TYPE_QUADROTOR, autopilot=M.MAV_AUTOPILOT_PX4,
        base_mode=M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | M.MAV_MODE_FLAG_STABILIZE_ENABLED,
        custom_mode=POSCTL_CUSTOM_MODE, system_status=M.MAV_STATE_BOOT, mavlink_version=3)


def boot_notice():
    return M.MAVLink_statustext_message(severity=M.MAV_SEVERITY_NOTICE, text=BOOT_TEXT.encode("ascii"),
                                        id=0, chunk_seq=0)


class _Peer:
    def __init__(self, sysid: int):
        self.mav = M.MAVLink(None, srcSystem=sysid, srcComponent=COMPID)
        self.mav.robust_parsing = True
        self.next_notice = 0.0


class BootLink:
    """Speaks for the rig on ``endpoints`` (opened :class:`~rig_emulator.link.endpoints.sockets.Endpoint`)
    in a thread until :meth:`hand_over`; see the module docstring."""

    def __init__(self, endpoints: list, sysid: int = 1):
        self.endpoints = endpoints
        self.sysid = sysid
        self.peers: dict = {}  # (id(endpoint), key) -> _Peer
        self.keys: dict = {id(ep): [] for ep in endpoints}  # peers in the order they appeared
        self.sent = 0
        self.rejected = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="hilms-boot-link", daemon=True)
        self._started = time.monotonic()

    def start(self) -> "BootLink":
        self._thread.start()
        return self

    def _send(self, ep, key, peer: _Peer, msg) -> None:
        buf = msg.pack(peer.mav)
        peer.mav.seq = (peer.mav.seq + 1) % 256
        if ep.send(key, bytes(buf)):
            self.sent += 1

    def _run(self) -> None:
        next_heartbeat = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            for ep in self.endpoints:
                for event, key, data in ep.poll():
                    pk = (id(ep), key)
                    if event == "open":
                        self.peers[pk] = _Peer(self.sysid)
                        self.keys[id(ep)].append(key)
                        self._send(ep, key, self.peers[pk], boot_heartbeat())
                    elif event == "closed":
                        self.peers.pop(pk, None)
                        if key in self.keys[id(ep)]:
                            self.keys[id(ep)].remove(key)
                    elif pk in self.peers:
                        self._receive(ep, key, self.peers[pk], data)
            heartbeat = now >= next_heartbeat
            if heartbeat:
                next_heartbeat = now + HEARTBEAT_PERIOD_S
            for (ep_id, key), peer in list(self.peers.items()):
                ep = next(e for e in self.endpoints if id(e) == ep_id)
                if heartbeat:
                    self._send(ep, key, peer, boot_heartbeat())
                if now >= peer.next_notice:
                    peer.next_notice = now + NOTICE_PERIOD_S
                    self._send(ep, key, peer, boot_notice())
            for ep in self.endpoints:
                ep.flush()
            socks = [s for ep in self.endpoints for s in ep.filenos()]
            timeout = max(0.0, min(next_heartbeat - time.monotonic(), 0.05))
            if socks:
                try:
                    select.select(socks, [], [], timeout)
                except (OSError, ValueError):  # a socket closed meanwhile
                    time.sleep(timeout)
            else:
                time.sleep(timeout)

    def _receive(self, ep, key, peer: _Peer, data: bytes) -> None:
        try:
            msgs = peer.mav.parse_buffer(data) or []
        except Exception:  # noqa: BLE001 - hostile bytes: the parser starts over
            peer.mav = _Peer(self.sysid).mav
            return
        if ep.datagram and peer.mav.buf_len():
            peer.mav = _Peer(self.sysid).mav
        for msg in msgs:
            kind = msg.get_type()
            if kind not in ("COMMAND_LONG", "COMMAND_INT"):
                continue
            if getattr(msg, "target_system", 0) not in (0, self.sysid):
                continue
            self._command(ep, key, peer, msg)

    def _command(self, ep, key, peer: _Peer, msg) -> None:
        wants_version = msg.command in _AUTOPILOT_VERSION_REQUESTS or (
            msg.command == M.MAV_CMD_REQUEST_MESSAGE and msg.param1 == M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
        if wants_version:
            self._send(ep, key, peer, M.MAVLink_command_ack_message(
                command=msg.command, result=M.MAV_RESULT_ACCEPTED, progress=0, result_param2=0,
                target_system=msg.get_srcSystem(), target_component=msg.get_srcComponent()))
            self._send(ep, key, peer, autopilot_version_message(self.sysid))
            return
        self.rejected += 1
        self._send(ep, key, peer, M.MAVLink_command_ack_message(
            command=msg.command, result=M.MAV_RESULT_TEMPORARILY_REJECTED, progress=0, result_param2=0,
            target_system=msg.get_srcSystem(), target_component=msg.get_srcComponent()))
        self._send(ep, key, peer, boot_notice())

    def hand_over(self) -> dict:
        """Stop speaking; returns ``{id(endpoint): [peer keys]}`` of the peers still connected."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5.0)
        for ep in self.endpoints:
            ep.flush()
        return {ep_id: list(keys) for ep_id, keys in self.keys.items()}
