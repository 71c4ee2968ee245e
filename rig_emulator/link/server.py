"""The MAVLink rig: a :class:`LiveRig` served on one or more endpoints.

The loop advances the physics in chunks (:attr:`RigServer.chunk_steps` steps, 5 ms of
simulated time by default) and works in ticks: it services the link (reads every endpoint,
handles each message at once: every command is ACKed before the next chunk), runs the
chunks that are due, builds after each chunk the streams due in that chunk's simulated
time (so stream rates hold in simulated time however often the link is serviced), and hands
the tick's frames to the sockets together (UDP: packed into few datagrams,
:mod:`rig_emulator.link.endpoints.sockets`). HEARTBEAT goes out at 1 Hz of wall-clock time.
With ``speedup`` > 0 the simulated clock is paced against ``time.monotonic()`` scaled by
the speed-up (1 = real time) and a tick runs the chunks due (one when on time, up to
:data:`CATCH_UP_CHUNKS` when behind); with ``speedup`` = 0 the rig runs as fast as it can,
a tick running chunks for :data:`TICK_WALL_S` of wall time (at most
:data:`CATCH_UP_CHUNKS`). When the host cannot keep up the pacing re-anchors instead of
bursting (counted in ``overruns``).

Bad input never stops the loop: unparsable bytes, bad CRCs, messages for other systems and
unusable fields are counted in :attr:`RigServer.counters` and dropped.

Optional: ``signing`` (:class:`~rig_emulator.link.signing.policy.LinkSigning`) signs every link and
rejects what is not signed with its key; ``state`` (:class:`~rig_emulator.link.state.rig_state.RigState`)
stores accepted parameter changes and missions before they are acknowledged.
"""

from __future__ import annotations

import math
import select
import time

from protocol.dialect import mavlink as M
from protocol.geodesy import Home
from rig_emulator.link.telemetry import status as telemetry_status
from rig_emulator.link.telemetry import units as U
from rig_emulator.link.endpoints.channel import Channel
from rig_emulator.link.commands.dedup import CommandDedup
from rig_emulator.link.commands import standard_modes
from rig_emulator.link.commands.command_long import Command, execute
from rig_emulator.link.commands.console import Console
from rig_emulator.link.commands.flight_control import FlightControl
from rig_emulator.link.commands.gcs_loss import GcsLoss
from rig_emulator.link.endpoints.counters import LinkCounters
from rig_emulator.link.endpoints.sockets import Endpoint, open_endpoint
from rig_emulator.headless.divergence import DivergenceWatch
from rig_emulator.headless.hover_thrust import HoverThrustEstimate
from rig_emulator.link.telemetry.fault_report import FaultReporter
from rig_emulator.link.ftp.component_metadata import metadata_files
from rig_emulator.link.commands.flight_monitors import FenceMonitor, OffboardLossMonitor
from rig_emulator.link.ftp.server import FileStore, FtpServer, reply_message
from rig_emulator.link.telemetry.ideal_sensors import load_sensor_model
from rig_emulator.link.mission.executor import MissionExecutor
from rig_emulator.link.mission.transfer import MissionTransfer
from rig_emulator.link.commands import flight_commands
from rig_emulator.link.commands.modes import FlightModes, split_custom_mode
from rig_emulator.link.commands.offboard_setpoints import OffboardSetpoints
from rig_emulator.link.commands.sysid_flight import SysidFlight
from rig_emulator.link.parameters.service import ParamService
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.link.signing.policy import refuse_setup_signing
from rig_emulator.link.telemetry.stream_table import ON_REQUEST, STREAMS, default_rates, group_members
from rig_emulator.link.telemetry.streams import StreamSchedule
from rig_emulator.link.telemetry.context import TelemetryContext

COMPID = M.MAV_COMP_ID_AUTOPILOT1
HEARTBEAT_PERIOD_S = 1.0
MAX_LAG_S = 0.25  # further behind real time than this: re-anchor the pacing
CATCH_UP_CHUNKS = 10  # at most this many chunks due at once are run before the link is serviced again
TICK_WALL_S = 0.01  # unpaced (speed-up 0): the link is serviced at least this often (wall-clock seconds)
STATUSTEXT_LEN = 50


class RigServer:
    def __init__(self, rig, endpoints: list[str], sysid: int = 1, home: Home | None = None,
                 speedup: float = 1.0, chunk_s: float = 0.005, signing=None, state=None, console: bool = False):
        if not 1 <= sysid <= 255:
            raise ValueError(f"sysid {sysid}: must be 1..255")
        if not (speedup >= 0.0 and math.isfinite(speedup)):
            raise ValueError(f"speedup {speedup}: must be >= 0 (0 = as fast as possible)")
        self.rig = rig
        self.sysid = sysid
        self.speedup = speedup
        self.chunk_steps = max(1, int(round(chunk_s / rig.dt)))
        self.chunk_s = self.chunk_steps * rig.dt
        self.counters = LinkCounters()
        self.modes = FlightModes()
        self.ctx = TelemetryContext(rig=rig, home=home or Home(35.7, 51.4, 1200.0), sensors=load_sensor_model(),
                                    modes=self.modes, counters=self.counters, sysid=sysid)
        self.signing = signing
        if signing is not None:
            signing.bind(self)
        # a controller plug-in's own parameters are served after the rig's (parameters/plugin_params.py)
        self.params = ParamService(rig, self, table=ParamTable(rig.controller, source=rig),
                                   store=state.params if state is not None else None)
        self.console = Console(enabled=console)
        self.flight = FlightControl(self)  # PX4's modes on the rig's guidance, arming checks, flight tasks
        self.ctx.flight = self.flight
        self.sysid_flight = SysidFlight(self)  # the identification flight (MAV_CMD_HILMS_SYSID, AUTO.SYSID)
        self.gcs_loss = GcsLoss()
        self.reboot_pending = False
        self.mission = MissionExecutor(self, store=state.mission if state is not None else None)
        self.ctx.mission = self.mission
        self.mission_transfer = MissionTransfer(self, self.mission)
        self.fault_reporter = FaultReporter()
        self.divergence = DivergenceWatch()  # onboard position vs SIM_STATE (headless/divergence.py)
        self.hover_thrust = HoverThrustEstimate()  # MPC_THR_HOVER (headless/hover_thrust.py)
        self.offboard = OffboardSetpoints(self)
        self.offboard_loss = OffboardLossMonitor(self, self.offboard)
        self.fence = FenceMonitor(self)
        self.ctx.fence = self.fence
        self.ftp = FtpServer(FileStore(metadata_files(rig.controller)))  # with the plug-in's parameters
        self.endpoints = []
        try:
            for spec in endpoints:  # connection strings, or endpoints opened already (a BootLink's)
                self.endpoints.append(spec if isinstance(spec, Endpoint) else open_endpoint(spec))
        except Exception:
            self.close()
            raise
        self.channels: dict[tuple, Channel] = {}
        self.overruns = 0
        #: --start-paused: the simulated clock holds until a mission is started (MISSION_START or
        #: AUTO.MISSION), so a scripted flight does not depend on when its set-up commands arrived
        self.hold_clock = False
        self.timing = None  # a rig_emulator.link.loop_timing.LoopTiming records every chunk's wall times
        self.command_dedup = CommandDedup()
        self.last_calibration = -math.inf  # wall-clock time of the last PREFLIGHT_CALIBRATION run
        self.heartbeat_pending = False
        self.clock_rebase = False
        self._stop = False
        self._snap = None
        self._statustext_id = 0
        self._next_heartbeat = 0.0
        self._handlers = {
            "HEARTBEAT": self._heartbeat_in,
            "PARAM_REQUEST_LIST": self.params.request_list,
            "PARAM_REQUEST_READ": self.params.request_read,
            "PARAM_SET": self.params.set,
            "COMMAND_LONG": lambda msg, ch: self._command(Command.from_long(msg), ch),
            "COMMAND_INT": lambda msg, ch: self._command(Command.from_int(msg), ch),
            "SET_MODE": self._set_mode_message,
            "REQUEST_DATA_STREAM": self._request_data_stream,
            **self.offboard.handlers(),  # SET_POSITION_TARGET_*, SET_ATTITUDE_TARGET, SET_ACTUATOR_CONTROL_TARGET
            "TIMESYNC": self._timesync,
            "FILE_TRANSFER_PROTOCOL": self._ftp,
            "SETUP_SIGNING": lambda msg, ch: refuse_setup_signing(self, msg, ch),
            **self.mission_transfer.handlers(),
        }

    # --- what tests and tools read ---------------------------------------------------------
    @property
    def urls(self) -> list[str]:
        """Connection strings of the endpoints with their bound ports."""
        return [ep.url for ep in self.endpoints]

    # --- sending -------------------------------------------------------------------------------
    def snapshot(self):
        if self._snap is None:
            self._snap = self.rig.snapshot()
        return self._snap

    def reply(self, channel: Channel, msg) -> None:
        channel.send(msg)

    def broadcast(self, msg) -> None:
        for ch in list(self.channels.values()):
            ch.send(msg)

    def statustext_messages(self, severity: int, text: str) -> list:
        """STATUSTEXT message(s) for ``text``, split into 50-character chunks."""
        data = text.encode("ascii", "replace")
        chunks = [data[i : i + STATUSTEXT_LEN] for i in range(0, len(data), STATUSTEXT_LEN)] or [b""]
        if len(chunks) > 1 and len(chunks[-1]) == STATUSTEXT_LEN:
            chunks.append(b"")
        msg_id = 0
        if len(chunks) > 1:
            self._statustext_id = self._statustext_id % 65535 + 1
            msg_id = self._statustext_id
        return [M.MAVLink_statustext_message(severity=severity, text=chunk, id=msg_id, chunk_seq=seq)
                for seq, chunk in enumerate(chunks)]

    def statustext(self, channel: Channel | None, severity: int, text: str) -> None:
        """STATUSTEXT to one peer (or all with ``None``: also a console line)."""
        if channel is None:
            self.console.statustext(self.rig.time_s, severity, text)
        for msg in self.statustext_messages(severity, text):
            self.broadcast(msg) if channel is None else channel.send(msg)

    def send_follow(self, channel: Channel, follow: list) -> None:
        """The messages that follow an answer to ``channel``: STATUSTEXT (a refusal's reason, a
        warning) to every peer and the console, as flight stacks log them; the rest (requested
        messages) to ``channel`` alone. In order, after the answer itself."""
        parts: list[bytes] = []
        for msg in follow:
            if msg.get_type() != "STATUSTEXT":
                channel.send(msg)
                continue
            self.broadcast(msg)
            text = msg.text if isinstance(msg.text, bytes) else str(msg.text).encode("ascii", "replace")
            parts.append(text.rstrip(b"\0"))
            if len(text) < STATUSTEXT_LEN or not msg.id:  # the last chunk of the text
                self.console.statustext(self.rig.time_s, msg.severity, b"".join(parts).decode("ascii", "replace"))
                parts = []

    def event(self, text: str) -> None:
        """An event of the flight (take-off, landing, return...): STATUSTEXT INFO to every peer and the console."""
        self.statustext(None, M.MAV_SEVERITY_INFO, text)

    def broadcast_heartbeat(self) -> None:
        self.broadcast(telemetry_status.heartbeat(self.rig.snapshot(), self.ctx))
        self.broadcast(standard_modes.current_mode(self.modes))

    def build(self, msg_id: int) -> list:
        """The message(s) ``msg_id`` for the current state (MAV_CMD_REQUEST_MESSAGE)."""
        self._snap = None
        out = ON_REQUEST[msg_id](self.snapshot(), self.ctx)
        return out if isinstance(out, list) else [out]

    # --- receiving ------------------------------------------------------------------------------
    def service_io(self) -> None:
        """Read every endpoint, handle what arrived, push queued bytes."""
        for ep in self.endpoints:
            for event, key, data in ep.poll():
                ck = (id(ep), key)
                if event == "open":
                    self._open_channel(ep, key)
                elif event == "closed":
                    self.channels.pop(ck, None)
                    self.ftp.forget(ck)
                elif ck in self.channels:
                    channel = self.channels[ck]
                    for msg in channel.receive(data):
                        self.handle(msg, channel)
        self.flush()
        if any(ep.dropped_peers for ep in self.endpoints):
            for ep in self.endpoints:
                self.counters.drop("peer_limit", ep.dropped_peers)
                ep.dropped_peers = 0

    def _open_channel(self, ep, key) -> None:
        sched = StreamSchedule(default_rates(), self.chunk_s)
        channel = Channel(ep, key, self.sysid, COMPID, self.counters, sched, self.signing)
        self.channels[(id(ep), key)] = channel
        channel.send(telemetry_status.heartbeat(self.snapshot(), self.ctx))

    def adopt_peers(self, peers: dict) -> None:
        """Channels for the peers a :class:`~rig_emulator.link.boot.BootLink` heard on these endpoints
        (``{id(endpoint): [keys]}``, from :meth:`BootLink.hand_over`); each gets a HEARTBEAT now."""
        for ep in self.endpoints:
            for key in peers.get(id(ep), []):
                if (id(ep), key) not in self.channels:
                    self._open_channel(ep, key)
        self.flush()

    def flush(self) -> None:
        """Hand what was queued to the sockets (UDP: the frames packed into datagrams); frames
        a socket could not take count as ``tx_overflow`` instead of sent."""
        for ep in self.endpoints:
            ep.flush()
            if ep.tx_dropped:
                self.counters.sent -= ep.tx_dropped
                self.counters.drop("tx_overflow", ep.tx_dropped)
                ep.tx_dropped = 0

    def handle(self, msg, channel: Channel) -> None:
        """Act on one decoded message from ``channel`` (or count why not)."""
        if msg.get_srcSystem() == self.sysid and msg.get_srcComponent() == COMPID:
            self.counters.drop("own_echo")
            return
        target = getattr(msg, "target_system", 0)
        if target not in (0, self.sysid):
            self.counters.drop("other_system")
            return
        if getattr(msg, "target_component", 0) not in (0, COMPID):
            self.counters.drop("other_component")
            return
        handler = self._handlers.get(msg.get_type())
        if handler is None:
            self.counters.drop("unhandled")
            return
        try:
            handler(msg, channel)
        except Exception as exc:  # noqa: BLE001 - a message must never stop the rig; counted and reported
            self.counters.drop("handler_error")
            self.statustext(channel, M.MAV_SEVERITY_ERROR, f"{msg.get_type()} failed: {exc}")

    def _command(self, cmd: Command, channel: Channel) -> None:
        self.counters.commands += 1
        result, follow = execute(cmd, self, channel)
        self._snap = None  # a command may have changed the rig (armed, mode, ...): the next reader sees it
        if result is None:  # a duplicated or overtaken copy of a command already answered
            return
        channel.send(M.MAVLink_command_ack_message(
            command=cmd.command, result=result, progress=0, result_param2=0,
            target_system=0, target_component=0))
        self.send_follow(channel, follow)
        if self.reboot_pending:
            self.reboot()
        if self.heartbeat_pending:
            self.heartbeat_pending = False
            self.broadcast_heartbeat()

    def _set_mode_message(self, msg, channel: Channel) -> None:
        """The legacy SET_MODE message (base_mode with MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, PX4's
        custom_mode): DO_SET_MODE's outcome, answered as PX4 does with a COMMAND_ACK for
        MAV_CMD_DO_SET_MODE."""
        if not int(msg.base_mode) & M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            result, follow = M.MAV_RESULT_DENIED, self.statustext_messages(
                M.MAV_SEVERITY_WARNING, "mode refused: SET_MODE needs MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and PX4's "
                                        "custom_mode")
        else:
            main, sub = split_custom_mode(int(msg.custom_mode))
            result, follow = flight_commands.set_mode(self, main, sub)
        self._snap = None
        channel.send(M.MAVLink_command_ack_message(command=M.MAV_CMD_DO_SET_MODE, result=result, progress=0,
                                                  result_param2=0, target_system=0, target_component=0))
        self.send_follow(channel, follow)
        if self.heartbeat_pending:
            self.heartbeat_pending = False
            self.broadcast_heartbeat()

    def _heartbeat_in(self, msg, channel: Channel) -> None:
        if self.gcs_loss.heard(msg):
            self.statustext(None, M.MAV_SEVERITY_INFO, "ground station regained")

    def reboot(self) -> None:
        """PREFLIGHT_REBOOT_SHUTDOWN: the simulation restarts from its initial state (time 0,
        disarmed, POSCTL) with the parameters and the mission kept; the process, its endpoints
        and every peer's stream rates stay."""
        self.reboot_pending = False
        t_old = self.rig.time_s
        self.statustext(None, M.MAV_SEVERITY_NOTICE, "rebooting: the simulation restarts")
        self.rig.reboot()
        self.flight.reset()
        self.mission.after_reboot()
        self.hover_thrust = HoverThrustEstimate()  # the thrust loop's correction starts afresh
        self.clock_restarted(t_old)
        self.clock_rebase = True
        self.heartbeat_pending = True
        self.console.line(self.rig.time_s, "rebooted")

    def clock_restarted(self, t_old: float) -> None:
        """The simulation restarted from simulated time ``t_old`` at 0 (a reboot, a flight stack's
        new session): every peer's streams move back with the clock, keeping their phase, and the
        fault report starts again from the new simulation's faults."""
        self.fault_reporter = FaultReporter()
        self._snap = None
        for ch in self.channels.values():
            ch.schedule.clock_restarted(t_old, self.rig.time_s)

    def _request_data_stream(self, msg, channel: Channel) -> None:
        hz = float(msg.req_message_rate) if msg.start_stop else 0.0
        for msg_id in group_members(msg.req_stream_id):
            channel.schedule.set_rate(msg_id, hz, self.rig.time_s)

    def _timesync(self, msg, channel: Channel) -> None:
        if msg.tc1 == 0:
            now_ns = max(U.time_ns(self.rig.sim.time_us), 1)  # tc1 = 0 would read as a request
            channel.send(M.MAVLink_timesync_message(tc1=now_ns, ts1=msg.ts1))

    def _ftp(self, msg, channel: Channel) -> None:
        """MAVFTP, read-only, serving the component metadata (:mod:`rig_emulator.link.ftp.server`)."""
        replies = self.ftp.handle(bytes(msg.payload), (id(channel.endpoint), channel.key))
        if replies is None:
            self.counters.drop("invalid")
            return
        for payload in replies:
            channel.send(reply_message(payload, msg))

    # --- the loop ------------------------------------------------------------------------------------
    def step_chunk(self) -> None:
        self.hover_thrust.update(self.rig.step(self.chunk_steps), self.rig)
        self.counters.steps += self.chunk_steps
        self._snap = None
        self.sysid_flight.poll()
        self.mission.poll()
        self.offboard_loss.poll()
        self.fence.poll()
        self.flight.poll(self.snapshot)
        self.report_faults()
        text = self.divergence.poll(self.rig)
        if text is not None:
            self.statustext(None, M.MAV_SEVERITY_NOTICE, text)
        self.console.poll(self.rig.time_s, self.rig.armed, self.modes.main, self.modes.sub)

    def report_faults(self) -> None:
        """STATUSTEXT for new fault injections and detections; a HEARTBEAT at once when the
        failsafe trips or clears (:mod:`rig_emulator.link.telemetry.fault_report`)."""
        texts, failsafe_changed = self.fault_reporter.poll(self.rig)
        for severity, text in texts:
            self.statustext(None, severity, text)
        if failsafe_changed:
            self.broadcast_heartbeat()

    def emit_streams(self) -> None:
        """Build the streams due now (each once, whichever peers it is due for) and queue them to their
        peers, in the peers' order and each peer's schedule order. Runs after every chunk (50 times a
        simulated second at ``--speedup max``), so its lookups are hoisted out of the loops."""
        now = self.rig.time_s
        built: dict[int, list] = {}
        snap = None
        ctx = self.ctx
        for ch in list(self.channels.values()):
            due = ch.schedule.due(now)
            if not due:
                continue
            send = ch.send
            for msg_id in due:
                msgs = built.get(msg_id)
                if msgs is None:
                    if snap is None:
                        snap = self.snapshot()
                    out = STREAMS[msg_id].build(snap, ctx)
                    msgs = built[msg_id] = out if isinstance(out, list) else (out,)
                for msg in msgs:
                    send(msg)

    def _heartbeat_if_due(self, now_wall: float) -> None:
        if now_wall >= self._next_heartbeat:
            self.broadcast_heartbeat()
            self._next_heartbeat = max(self._next_heartbeat + HEARTBEAT_PERIOD_S, now_wall + 0.5 * HEARTBEAT_PERIOD_S)

    def _wait_io(self, timeout: float) -> None:
        socks = [s for ep in self.endpoints for s in ep.filenos()]
        if timeout > 0 and socks:
            select.select(socks, [], [], timeout)
        elif timeout > 0:
            time.sleep(timeout)

    def stop(self) -> None:
        """Ask the loop to finish (safe from a signal handler)."""
        self._stop = True

    def run(self, duration: float | None = None) -> None:
        """Serve until :meth:`stop` or until ``duration`` more simulated seconds have passed."""
        t_end = math.inf if duration is None else self.rig.time_s + duration - 0.5 * self.rig.dt
        wall0 = time.monotonic()
        sim0 = self.rig.time_s
        self._next_heartbeat = wall0
        busy, window_start = 0.0, wall0
        while not self._stop and self.rig.time_s < t_end:
            t0 = time.monotonic()
            self._heartbeat_if_due(t0)
            self.service_io()
            self.gcs_loss.check(self)
            if self.clock_rebase:  # a reboot restarted the simulated clock
                self.clock_rebase = False
                wall0, sim0 = time.monotonic(), self.rig.time_s
            self.mission_transfer.tick(t0)
            if self.signing is not None:
                self.signing.tick(t0)
            if self.hold_clock:
                if self.mission.state != M.MISSION_STATE_ACTIVE:
                    busy += time.monotonic() - t0
                    self._wait_io(min(0.02, max(self._next_heartbeat - t0, 0.0)))
                    continue
                self.hold_clock = False
                wall0, sim0 = time.monotonic(), self.rig.time_s
            if self.speedup > 0.0:
                lag = sim0 + (t0 - wall0) * self.speedup - self.rig.time_s
                if lag < self.chunk_s:
                    busy += time.monotonic() - t0
                    wait = min((self.chunk_s - lag) / self.speedup, max(self._next_heartbeat - t0, 0.0))
                    self._wait_io(wait)
                    continue
                if lag > MAX_LAG_S * max(self.speedup, 1.0):
                    wall0, sim0 = t0, self.rig.time_s
                    self.overruns += 1
                    self.counters.pacing_reset(lag)
                    lag = self.chunk_s
            # One tick: the chunks that are due (behind schedule, e.g. after a flood of input or a slow
            # request: up to CATCH_UP_CHUNKS) or, unpaced, as many as fit in TICK_WALL_S; each chunk
            # builds the telemetry due in its own simulated time (rates hold however the loop is
            # serviced), and the tick's frames go to the sockets together (packed datagrams).
            if self.speedup > 0.0:
                n_chunks = max(1, min(int(lag / self.chunk_s), CATCH_UP_CHUNKS))
            else:
                n_chunks = CATCH_UP_CHUNKS
            tick_end = t0 + TICK_WALL_S
            for _ in range(n_chunks):
                if self.rig.time_s >= t_end:
                    break
                if self.timing is not None:
                    self.timing.begin(wall0, sim0, self.rig.time_s)
                self.step_chunk()
                self.emit_streams()
                if self.speedup <= 0.0 and time.monotonic() >= tick_end:
                    break
            self.flush()
            t1 = time.monotonic()
            busy += t1 - t0
            if self.timing is not None:
                self.timing.finish(t1, self.counters.sent)
            if t1 - window_start >= 1.0:
                self.ctx.load_fraction = min(busy / (t1 - window_start), 1.0)
                busy, window_start = 0.0, t1
        self._drain()

    def _drain(self, timeout_s: float = 0.5) -> None:
        """Give queued TCP bytes (e.g. the last ACKs) a moment to leave before closing."""
        self.flush()
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and any(
                getattr(c, "tx", None) for ep in self.endpoints for c in getattr(ep, "clients", {}).values()):
            for ep in self.endpoints:
                ep.flush()
            time.sleep(0.005)

    def close(self) -> None:
        for ep in self.endpoints:
            ep.close()
        self.endpoints = []
        self.channels = {}
