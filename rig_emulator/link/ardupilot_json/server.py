"""``rig-emulator serve --ardupilot-json ...``: the rig as the physics of ArduPilot SITL
(``arducopter --model JSON:HOST``), with the ground link still served.

One loop, one thread: it waits (``select``) on the UDP socket ArduPilot sends its servo
packets to (port 9002 by default, where ``SIM_JSON`` sends) and on the ground link's
sockets. Each packet is answered at once, to the address it came from
(:mod:`rig_emulator.link.ardupilot_json.session`: a new frame steps the plant, a repeated one
is answered again without stepping); the ground link is serviced between packets
(:mod:`rig_emulator.link.ground_beside`).

Sessions: the first packet of an ArduPilot starts one (the plant starts afresh). A packet from
another address, or whose ``frame_count`` went back (ArduPilot restarted), starts a new one,
if the running session's ArduPilot has been silent for :data:`SILENT_S` or the newcomer has
just started (``frame_count`` 0); otherwise it is refused (not answered; counted in
``refused``): one ArduPilot at a time. A session whose ArduPilot is silent for
:data:`SILENT_S` ends (motors off); if the same ArduPilot carries on with its next frames, the
session resumes where it was. Datagrams that are not servo packets are counted
(``bad_data``) and not answered.

The rig's own controllers do not run in this mode: ArduPilot drives the motors.
"""

from __future__ import annotations

import math
import select
import socket
import time

from rig_emulator.link.ardupilot_json import servo_packet
from rig_emulator.link.ardupilot_json.session import JsonSession
from rig_emulator.link.ground_beside import GroundBeside

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 9002  # SIM_JSON's control port (+ 10 per SITL instance, -I N)
SILENT_S = 5.0  # an ArduPilot that sends nothing for this long (wall clock) has gone
MAX_PACKETS_PER_WAKE = 64  # datagrams read in one go before the ground link gets a turn
RECV_BYTES = 2048


class JsonPhysicsServer:
    def __init__(self, ground, host: str, port: int, plant, log=print):
        self.ground = ground
        self.ground_link = GroundBeside(ground)
        self.plant = plant
        self._log = log
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind((host, port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)
        self.session: JsonSession | None = None
        self.sessions = 0
        self.session_steps: list[int] = []  # steps of every session that ended
        self.refused = 0
        self.bad_packets = 0
        self._gone = False  # the running session's ArduPilot fell silent (the session is over until it speaks)
        self._refused_from = None
        self._stop = False

    @property
    def url(self) -> str:
        host, port = self.sock.getsockname()[:2]
        return f"udp:{host}:{port}"

    def stop(self) -> None:
        """Ask the loop to finish (safe from a signal handler)."""
        self._stop = True

    # --- sessions -------------------------------------------------------------------------
    def _start_session(self, addr, packet) -> JsonSession:
        if self.session is not None and not self._gone:
            self._end_session("replaced")
        self.sessions += 1
        t_old = self.plant.time_s
        self.session = JsonSession(addr, self.plant, self.ground.counters, log=self._log)
        self._gone = False
        self.ground_link.plant_restarted(t_old)
        self._log(f"ArduPilot at udp:{addr[0]}:{addr[1]} (frame {packet.frame_count}, {len(packet.pwm_us)} "
                  f"channels, {packet.frame_rate_hz} Hz asked); the plant starts afresh, "
                  f"{1.0 / self.plant.period_s:g} Hz steps")
        return self.session

    def _end_session(self, why: str) -> None:
        s = self.session
        s.close()
        self._gone = True
        self.session_steps.append(s.steps)
        self._log(f"ArduPilot at udp:{s.addr[0]}:{s.addr[1]} {why} at t = {self.plant.time_s:.3f} s after "
                  f"{s.steps} frames ({s.repeats} repeated, {s.missed} missed); motors off")

    def _session_for(self, addr, packet, now: float) -> JsonSession | None:
        """The session this packet belongs to (a new one if it starts one); None: refused."""
        s = self.session
        if s is not None and addr == s.addr and packet.frame_count >= s.last_frame:
            if self._gone:
                self._gone = False
                self._log(f"ArduPilot at udp:{addr[0]}:{addr[1]} back at frame {packet.frame_count}")
            return s
        if s is None or self._gone or packet.frame_count == 0 or now - s.last_heard >= SILENT_S:
            return self._start_session(addr, packet)
        self.refused += 1
        if addr != self._refused_from:
            self._refused_from = addr
            self._log(f"refused servo packets from udp:{addr[0]}:{addr[1]} (frame {packet.frame_count}): "
                      f"serving the ArduPilot at udp:{s.addr[0]}:{s.addr[1]}")
        return None

    # --- packets ----------------------------------------------------------------------------
    def _read_packets(self, now: float) -> None:
        sock, counters = self.sock, self.ground.counters
        for _ in range(MAX_PACKETS_PER_WAKE):
            try:
                data, addr = sock.recvfrom(RECV_BYTES)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # ICMP port unreachable from an earlier answer: ArduPilot went away
                continue
            counters.rx_bytes += len(data)
            try:
                packet = servo_packet.decode(data)
            except servo_packet.PacketError as exc:
                self.bad_packets += 1
                counters.drop("bad_data")
                if self.bad_packets == 1:
                    self._log(f"not a servo packet from udp:{addr[0]}:{addr[1]}: {exc}")
                continue
            counters.received += 1
            s = self._session_for(addr[:2], packet, now)
            if s is None:
                continue
            s.last_heard = now
            reply = s.answer(packet)
            try:
                sock.sendto(reply, addr)
                counters.sent += 1
            except OSError:
                counters.drop("tx_overflow")

    # --- the loop ---------------------------------------------------------------------------
    def run(self, duration: float | None = None) -> None:
        """Serve until :meth:`stop`, or until a session has run ``duration`` simulated seconds."""
        t_end = math.inf if duration is None else duration - 0.5 * self.plant.period_s
        link = self.ground_link
        link.next_at = time.monotonic()
        select_, monotonic = select.select, time.monotonic
        ground = None
        fds = None
        while not self._stop:
            now = monotonic()
            if now >= link.next_at:
                link.service(now)
                ground = None
                s = self.session
                if s is not None and not self._gone and now - s.last_heard >= SILENT_S:
                    self._end_session(f"silent for {SILENT_S:g} s")
            if self.session is not None and not self._gone and self.plant.time_s >= t_end:
                break
            if ground is None:
                ground = link.sockets()
                fds = [self.sock] + ground
            readable = select_(fds, [], [], max(link.next_at - now, 0.0))[0]
            if not readable:
                continue
            if self.sock in readable:
                self._read_packets(monotonic())
            if ground and any(sock in readable for sock in ground):
                link.service(monotonic())
                ground = None
        if self.session is not None and not self._gone:
            self._end_session("left (the rig stops)")

    def close(self) -> None:
        if self.session is not None and not self._gone:
            self._end_session("left (the rig stops)")
        self.sock.close()
