"""``rig-emulator serve --px4-simulator ...``: the rig as the simulator of a flight stack,
with the ground link still served.

One loop, one thread: it waits (``select``) on the flight stack's stream, the listening
socket and the ground link's sockets. The flight stack's messages step the plant
(:mod:`rig_emulator.link.px4_simulator.session`); the ground link is serviced between steps
(:mod:`rig_emulator.link.ground_beside`).

The rig's own controllers do not run in this mode: the flight stack drives the motors.
"""

from __future__ import annotations

import math
import select
import time

from rig_emulator.link.ground_beside import GroundBeside
from rig_emulator.link.px4_simulator.session import SimulatorSession


class Px4SimulatorServer:
    def __init__(self, ground, transport, plant, home, speedup: float = 1.0, all_fields: bool = False, log=print):
        self.ground = ground
        self.ground_link = GroundBeside(ground)
        self.transport = transport
        self.plant = plant
        self.home = home
        self.speedup = speedup
        self.all_fields = all_fields
        self._log = log
        self.session: SimulatorSession | None = None
        self.sessions = 0
        self.session_steps: list[int] = []  # steps of every finished session
        self._stop = False

    def stop(self) -> None:
        """Ask the loop to finish (safe from a signal handler)."""
        self._stop = True

    # --- sessions -------------------------------------------------------------------------
    def _start_session(self, conn) -> None:
        self.sessions += 1
        t_old = self.plant.time_s
        self.session = SimulatorSession(conn, self.plant, self.home, speedup=self.speedup,
                                        all_fields=self.all_fields, counters=self.ground.counters, log=self._log)
        self.ground_link.plant_restarted(t_old)
        self._log(f"flight stack connected ({conn.name}); the plant starts afresh")

    def _end_session(self) -> None:
        s = self.session
        self.session = None
        s.close()
        self.session_steps.append(s.steps)
        self._log(f"flight stack gone ({s.conn.name}) at t = {self.plant.time_s:.3f} s after {s.steps} steps "
                  f"({s.actuator_messages} actuator messages); motors off, waiting for the next one")

    # --- the loop ---------------------------------------------------------------------------
    def run(self, duration: float | None = None) -> None:
        """Serve until :meth:`stop`, or until a session has run ``duration`` simulated seconds.

        In lockstep an iteration is one step (the flight stack's answer read and acted on): the
        sockets waited on are collected again only when they may have changed (after a ground
        service, which accepts and drops ground stations, or when a session starts or ends)."""
        t_end = math.inf if duration is None else duration - 0.5 * self.plant.period_s
        timed = duration is not None
        link = self.ground_link
        link.next_at = time.monotonic()
        listening = self.transport.filenos()
        fds = ground = None
        fds_session = None
        select_ = select.select
        monotonic = time.monotonic
        while not self._stop:
            now = monotonic()
            if now >= link.next_at:
                link.service(now)
                ground = None
            s = self.session
            if s is not None:
                if not s.lockstep:
                    # what the flight stack sent first: an answer that has arrived starts lockstep before
                    # a late free-run step would (the loop may wake late on a busy machine)
                    due = s.free_run_due(now)  # once: it re-anchors the free run after a long stall
                    if due and select_([s.conn], [], [], 0)[0]:
                        if not s.on_readable():
                            self._end_session()
                            continue
                        if s.lockstep:
                            due = 0
                    for _ in range(due):
                        s.step()
                if not s.conn.open:
                    self._end_session()
                    continue
            elif not listening:  # a serial line: open it (again) when it can be
                self._accept()
            s = self.session
            if timed and s is not None and self.plant.time_s >= t_end:
                break
            if ground is None or fds_session is not s:
                ground = link.sockets()
                fds = ground + listening + ([s.conn] if s is not None else [])
                fds_session = s
            timeout = link.next_at - now
            if timeout < 0.0:
                timeout = 0.0
            if s is not None:
                free = None if s.lockstep else s.next_free_run_in(now)
                if free is not None and free < timeout:
                    timeout = free
            elif not listening:
                timeout = min(timeout, 0.05)
            readable = select_(fds, [], [], timeout)[0]
            if not readable:
                continue
            # the session first: a flight stack that closed and reconnected at once is over before the new one
            if s is not None and s.conn in readable and not s.on_readable():
                self._end_session()
            if listening and listening[0] in readable:
                self._accept()
            if ground and any(sock in readable for sock in ground):
                link.service(monotonic())
                ground = None
        if self.session is not None:
            self._end_session()

    def _accept(self) -> None:
        s = self.session
        if s is not None and select.select([s.conn], [], [], 0)[0] and not s.on_readable():
            self._end_session()  # the flight stack that is calling again has closed its old connection
        conn = self.transport.accept(busy=self.session is not None)
        if conn is not None:
            self._start_session(conn)

    def close(self) -> None:
        if self.session is not None:
            self._end_session()
        self.transport.close()
