"""Start a MAVLink rig on free ports from tests and scripts, and connect pymavlink clients.

Two ways to run a rig:

* :class:`RigProcess` - ``python -m rig_emulator serve`` in a subprocess (the real
  command line; use it for signals, exit codes and external tools such as MAVProxy).
  Endpoints bind port 0 and the rig prints the bound ports, so there is no port race::

      with RigProcess(speedup=5) as rig:
          conn = connect(rig.tcp_url)      # a pymavlink connection to the rig
          ...
          assert rig.stop() == 0

* :class:`RigThread` - a :class:`~rig_emulator.link.server.RigServer` in a thread of the
  test process, which exposes the server (``rig.server.counters``, ``rig.server.rig``)::

      with RigThread(speedup=0) as rig:
          conn = connect(rig.tcp_url)

Client helpers: ``recv`` (next matching message), ``recv_text`` (next STATUSTEXT, chunks
joined), ``command`` (COMMAND_LONG -> its ACK), ``start_offboard`` (a set-point, then OFFBOARD),
``all_params`` (the whole parameter table), ``collect`` / ``count_in_window`` /
``stamp_s`` (count messages against their own simulated-time stamps).

``connect`` opens a pymavlink ``mavutil`` connection speaking the hilms dialect over
MAVLink 2 (client sysid 255 by default; ``signing_key=`` signs it with pymavlink's
``setup_signing``). ``udp_listener`` opens a UDP socket for a rig ``udpout`` endpoint
*before* the rig starts (pass ``extra_endpoints=[listener_url]``).

State: every :class:`RigProcess` gets a state directory of its own (a fresh temporary one,
removed at :meth:`~RigProcess.stop`, unless ``state_dir=`` names one or ``args`` has
``--state-dir`` / ``--no-persist``), so rigs never share stored parameters or missions.
:class:`RigThread` stores nothing unless given ``state_dir=``.
"""

from __future__ import annotations

import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict

from protocol.dialect import use_hilms_dialect

START_TIMEOUT_S = 240.0  # a cold numba cache compiles the step loop first (about 1-2 min under load)
# Served rigs fly the product's default plant, the hardware rig (`hilms`): what users fly. A test
# that needs the ideal physics passes ``airframe="hilms-ideal"`` and says why.
TEST_AIRFRAME = "hilms"
NAN = float("nan")


def client_url(rig_url: str) -> str:
    """The mavutil string a client uses to reach a rig endpoint URL."""
    kind, host, port = rig_url.split(":")
    if kind == "tcpin":
        return f"tcp:{host}:{port}"
    if kind in ("udpin", "udp"):
        return f"udpout:{host}:{port}"
    if kind == "udpout":
        return f"udpin:{host}:{port}"
    raise ValueError(f"{rig_url!r}: no client form for this endpoint kind")


def connect(rig_url: str, source_system: int = 255, source_component: int = 190, signing_key: bytes | None = None,
            **signing):
    """A pymavlink connection (hilms dialect, MAVLink 2) to a rig endpoint URL; with
    ``signing_key`` it signs what it sends and checks what it receives (``signing`` are
    further ``setup_signing`` arguments: ``link_id``, ``initial_timestamp``, ...)."""
    use_hilms_dialect()
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection(client_url(rig_url), source_system=source_system,
                                      source_component=source_component, autoreconnect=False)
    if signing_key is not None:
        conn.setup_signing(signing_key, sign_outgoing=True, **signing)
    return conn


def udp_listener(source_system: int = 255):
    """A client listening on a free UDP port; returns (connection, rig endpoint URL to use)."""
    use_hilms_dialect()
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=source_system)
    port = conn.port.getsockname()[1]
    return conn, f"udpout:127.0.0.1:{port}"


def recv(conn, types, timeout: float = 10.0, condition=None):
    """The next message of ``types`` (str or list) satisfying ``condition``, or None after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = conn.recv_match(type=types, blocking=True, timeout=min(0.2, max(deadline - time.monotonic(), 0.01)))
        if msg is not None and (condition is None or condition(msg)):
            return msg
    return None


def recv_text(conn, condition=None, timeout: float = 10.0):
    """The next STATUSTEXT whose whole text (MAVLink 2 chunks joined by ``id``) satisfies
    ``condition(text)``; returns ``(severity, text)`` or None after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    parts: dict[int, list] = {}
    while time.monotonic() < deadline:
        m = recv(conn, "STATUSTEXT", max(deadline - time.monotonic(), 0.01))
        if m is None:
            return None
        text = m.text if isinstance(m.text, str) else m.text.decode("ascii", "replace")
        if m.id:
            parts.setdefault(m.id, []).append(text)
            if len(text) == 50:  # more chunks follow
                continue
            text = "".join(parts.pop(m.id))
        if condition is None or condition(text):
            return m.severity, text
    return None


def stamp_s(msg) -> float | None:
    """The message's own simulated-time stamp in seconds (None if it has none)."""
    if hasattr(msg, "time_usec"):
        return msg.time_usec * 1e-6
    if hasattr(msg, "time_boot_ms"):
        return msg.time_boot_ms * 1e-3
    return None


def collect(conn, sim_seconds: float, guard_s: float = 60.0, clock="ATTITUDE") -> dict:
    """Messages by type until the ``clock`` stream's stamps have advanced ``sim_seconds``."""
    out = defaultdict(list)
    first = None
    deadline = time.monotonic() + guard_s
    while time.monotonic() < deadline:
        msg = conn.recv_match(blocking=True, timeout=0.2)
        if msg is None:
            continue
        out[msg.get_type()].append(msg)
        if msg.get_type() == clock:
            t = stamp_s(msg)
            first = t if first is None else first
            if t - first >= sim_seconds:
                break
    return out


def count_in_window(msgs, t0: float, t1: float) -> int:
    return sum(1 for m in msgs if t0 <= stamp_s(m) < t1)


def command(conn, cmd: int, *params, target=(1, 1), confirmation=0, timeout=10.0):
    """Send a COMMAND_LONG (params padded with NaN) and return its COMMAND_ACK."""
    p = list(params) + [NAN] * (7 - len(params))
    conn.mav.command_long_send(target[0], target[1], cmd, confirmation, *p)
    return recv(conn, "COMMAND_ACK", timeout, lambda m: m.command == cmd)


def start_offboard(conn, send_setpoint, target=(1, 1), timeout=10.0, period_s=0.02):
    """PX4's offboard start, as MAVSDK's ``offboard.start()`` does it: a set-point first
    (``send_setpoint()``; the stream must already flow), then DO_SET_MODE OFFBOARD, the stream
    kept up (every ``period_s`` of wall time) until the answer: a rig far faster than real time
    that enters OFFBOARD before this client has read its backlog would otherwise see the stream
    stop and hold (COM_OF_LOSS_T). Returns the COMMAND_ACK (None on timeout)."""
    from protocol.dialect import mavlink as M

    ack = None
    for _ in range(3):  # a refusal (the set-point judged stale by a rig running far faster than real time) retries
        send_setpoint()
        p = [M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 6, 0] + [NAN] * 4
        conn.mav.command_long_send(target[0], target[1], M.MAV_CMD_DO_SET_MODE, 0, *p)
        ack, deadline = None, time.monotonic() + timeout
        while ack is None and time.monotonic() < deadline:
            m = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=period_s)
            if m is not None and m.command == M.MAV_CMD_DO_SET_MODE:
                ack = m
            else:
                send_setpoint()
        if ack is None or ack.result != M.MAV_RESULT_DENIED:
            break
    return ack


def all_params(conn, timeout=10.0) -> dict:
    """PARAM_REQUEST_LIST: {index: PARAM_VALUE} until the table is complete (or timeout)."""
    conn.mav.param_request_list_send(1, 1)
    got = {}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = recv(conn, "PARAM_VALUE", 1.0)
        if m is None:
            break
        got[m.param_index] = m
        if len(got) == m.param_count:
            break
    return got



class _RigBase:
    urls: list

    @property
    def tcp_url(self) -> str:
        return next(u for u in self.urls if u.startswith("tcpin:"))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


class RigProcess(_RigBase):
    """``rig-emulator serve`` as a subprocess with a tcpin endpoint on a free port."""

    def __init__(self, speedup: float | str = 1.0, extra_endpoints=(), args=(), tcp: bool = True, state_dir=None,
                 airframe: str | None = TEST_AIRFRAME, wait_ready: bool = True, env=None):
        """Starts the rig and returns once it printed its endpoints' URLs and, with ``wait_ready``,
        ``rig-emulator: ready`` (its step loop compiled; before that it answers as starting, in
        MAV_STATE_BOOT: :mod:`rig_emulator.link.boot`). ``env``: extra environment variables."""
        endpoints = (["tcpin:127.0.0.1:0"] if tcp else []) + list(extra_endpoints)
        cmd = [sys.executable, "-m", "rig_emulator", "serve", "--speedup", str(speedup)]
        if airframe is not None and not any(str(a).startswith("--airframe") for a in args):
            cmd += ["--airframe", airframe]
        for ep in endpoints:
            cmd += ["--mavlink", ep]
        cmd += list(args)
        self._own_state_dir = None
        if state_dir is not None:
            cmd += ["--state-dir", str(state_dir)]
        elif not any(a in ("--state-dir", "--no-persist") or str(a).startswith("--state-dir=") for a in args):
            self._own_state_dir = tempfile.mkdtemp(prefix="hilms-rig-state-")
            cmd += ["--state-dir", self._own_state_dir]
        env = dict(os.environ, PYTHONUNBUFFERED="1", **(env or {}))
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        self._lines: queue.Queue = queue.Queue()
        self.output: list[str] = []
        threading.Thread(target=self._pump, daemon=True).start()
        self.urls = []
        deadline = time.monotonic() + START_TIMEOUT_S
        while len(self.urls) < len(endpoints):
            try:
                line = self._lines.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                self.proc.kill()
                self._remove_own_state_dir()
                raise RuntimeError(f"rig did not start: {self.proc.stderr.read()}") from None
            if line is None:
                self._remove_own_state_dir()
                raise RuntimeError(f"rig exited with {self.proc.wait()}: {self.proc.stderr.read()}")
            if line.startswith("rig-emulator: serving "):
                self.urls.append(line.split()[-1])
        self.ready = False
        if wait_ready:
            try:
                self.wait_ready(max(deadline - time.monotonic(), 0.01))
            except RuntimeError:
                self.stop(signal.SIGKILL)
                raise

    def wait_ready(self, timeout: float = START_TIMEOUT_S) -> None:
        """Wait for the ``rig-emulator: ready`` line (RuntimeError when the rig exits or ``timeout`` passes)."""
        deadline = time.monotonic() + timeout
        while not self.ready:
            try:
                line = self._lines.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                raise RuntimeError(f"rig not ready within {timeout:g} s: {self.output[-5:]}") from None
            if line is None:
                self._remove_own_state_dir()
                raise RuntimeError(f"rig exited with {self.proc.wait()}: {self.proc.stderr.read()}")
            if line.startswith("rig-emulator: ready"):
                self.ready = True

    def wait_line(self, prefix: str, timeout: float = 60.0) -> str | None:
        """The first line of the rig's output starting with ``prefix``, once it is there (None after
        ``timeout``: a bound, not a measure)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.output):
                if line.startswith(prefix):
                    return line
            time.sleep(0.02)
        return None

    def _pump(self) -> None:
        for line in self.proc.stdout:
            self.output.append(line.rstrip("\n"))
            self._lines.put(line.strip())
        self._lines.put(None)

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 30.0) -> int:
        """Send ``sig`` and return the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._remove_own_state_dir()
        return self.proc.returncode

    def _remove_own_state_dir(self) -> None:
        if self._own_state_dir is not None:
            shutil.rmtree(self._own_state_dir, ignore_errors=True)
            self._own_state_dir = None


class RigThread(_RigBase):
    """A :class:`RigServer` running in a daemon thread of this process."""

    def __init__(self, speedup: float = 1.0, extra_endpoints=(), overrides=None, scenario=None, sysid: int = 1,
                 signing_key: bytes | None = None, state_dir=None, airframe: str = TEST_AIRFRAME, controller=None):
        from rig_emulator.config.loader import load_config
        from rig_emulator.link.state.rig_state import RigState
        from rig_emulator.link.serve import prepare_rig
        from rig_emulator.link.server import RigServer
        from rig_emulator.link.signing.policy import LinkSigning

        cfg = load_config(airframe=airframe, scenario=scenario, overrides=overrides or {})
        rig = prepare_rig(cfg, controller)  # controller: a plug-in object
        self.state = None if state_dir is None else RigState(state_dir, None)
        signing = None
        if signing_key is not None:
            signing = LinkSigning(signing_key, stored=self.state and self.state.signing_stored,
                                  save=self.state and self.state.save_signing)
        self.server = RigServer(rig, ["tcpin:127.0.0.1:0", *extra_endpoints], sysid=sysid, speedup=speedup,
                                signing=signing, state=self.state)
        if self.state is not None:
            self.state.restore(self.server)
        self.urls = self.server.urls
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self.server.run()
        except BaseException as exc:  # noqa: BLE001 - reported to the test through self.error
            self.error = exc

    def stop(self) -> None:
        self.server.stop()
        self._thread.join(30.0)
        self.server.close()
        if self.server.signing is not None:
            self.server.signing.close()
        if self.state is not None:
            self.state.close()
        if self.error is not None:
            raise self.error


class MissionClient:
    """A ground-station side of the mission protocol over a pymavlink connection, following
    the spec's retry rules (for tests and the transfer benchmark; the ground tools have
    their own in ``gcs_tools``).

    Upload: MISSION_COUNT, then each requested item as MISSION_ITEM_INT, until MISSION_ACK.
    A reply missing for ``retry_s`` makes it send again what the rig has not acknowledged
    (the count before the first request, else the last requested item); ``max_retries``
    silent retries in a row abort with ``TimeoutError``. Download: MISSION_REQUEST_LIST,
    then each item with MISSION_REQUEST_INT (``window`` requests in flight), then MISSION_ACK.
    Messages of other types are skipped; duplicated or stale replies are ignored.
    """

    def __init__(self, conn, target=(1, 1), retry_s: float = 0.25, max_retries: int = 20, window: int = 1):
        self.conn = conn
        self.target = target
        self.retry_s = retry_s
        self.max_retries = max_retries
        self.window = max(1, window)
        self.retries = 0  # resends done by this client (figures for the lossy-link test)

    def _wait(self, types, condition=None):
        return recv(self.conn, types, self.retry_s, condition)

    def upload(self, items, mission_type: int = 0) -> int:
        """Send ``items`` (MissionItem, seq 0..N-1); returns the rig's MISSION_ACK type."""
        from protocol.mission_items import item_to_int_message

        ts, tc = self.target
        msgs = [item_to_int_message(it, ts, tc) for it in items]
        self.conn.mav.mission_count_send(ts, tc, len(msgs), mission_type)
        last = None  # the seq the rig asked for most recently
        sent_last_item = not msgs
        silent = 0
        while True:
            m = self._wait(["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"],
                           lambda m: getattr(m, "mission_type", 0) == mission_type)
            if m is None:
                silent += 1
                if silent > self.max_retries:
                    raise TimeoutError(f"mission upload: no answer after {self.max_retries} retries")
                self.retries += 1
                if last is None:
                    self.conn.mav.mission_count_send(ts, tc, len(msgs), mission_type)
                else:
                    self.conn.mav.send(msgs[last])
                continue
            silent = 0
            if m.get_type() == "MISSION_ACK":
                if m.type != 0 or sent_last_item:
                    return m.type
                continue  # an ACCEPTED before our last item: a stale ACK of an earlier operation
            if m.seq < len(msgs):
                last = m.seq
                self.conn.mav.send(msgs[m.seq])
                sent_last_item = sent_last_item or m.seq == len(msgs) - 1

    def download(self, mission_type: int = 0) -> list:
        """The rig's items (MissionItem) in seq order."""
        from protocol.mission_items import item_from_message

        ts, tc = self.target
        silent = 0
        self.conn.mav.mission_request_list_send(ts, tc, mission_type)
        while True:
            m = self._wait("MISSION_COUNT", lambda m: m.mission_type == mission_type)
            if m is not None:
                break
            silent += 1
            if silent > self.max_retries:
                raise TimeoutError(f"mission download: no MISSION_COUNT after {self.max_retries} retries")
            self.retries += 1
            self.conn.mav.mission_request_list_send(ts, tc, mission_type)
        count = m.count
        got: dict = {}
        sent: dict = {}
        low = 0  # lowest seq not received yet
        silent = 0
        while low < count:
            now = time.monotonic()
            for seq in range(low, min(count, low + self.window)):
                if seq not in got and now - sent.get(seq, -1e9) >= self.retry_s:
                    self.retries += seq in sent
                    self.conn.mav.mission_request_int_send(ts, tc, seq, mission_type)
                    sent[seq] = now
            m = self._wait("MISSION_ITEM_INT", lambda m: m.mission_type == mission_type)
            if m is None:
                silent += 1
                if silent > self.max_retries:
                    raise TimeoutError(f"mission download: item {low} missing after {self.max_retries} retries")
                continue
            silent = 0
            if m.seq < count and m.seq not in got:
                got[m.seq] = item_from_message(m)
            while low < count and low in got:
                low += 1
        self.conn.mav.mission_ack_send(ts, tc, 0, mission_type)
        return [got[s] for s in range(count)]


class NullEndpoint:
    """An endpoint that takes every frame and sends nothing: drives a :class:`~rig_emulator.link.server.RigServer`
    channel chunk by chunk in a test, without a socket."""

    kind = "udpin"
    datagram = True

    def send(self, key, data) -> bool:
        return True

    def flush(self) -> None:
        pass


def capture_channel(server):
    """Attach a peer to ``server`` (a :class:`NullEndpoint` channel at the default stream rates) that keeps
    every message the rig sends it: (the channel, the list of those messages in order). A test hands
    messages to ``server.handle(msg, channel)``, steps chunks on the server itself and reads what a ground
    station would have received."""
    from rig_emulator.link.endpoints.channel import Channel
    from rig_emulator.link.telemetry.stream_table import default_rates
    from rig_emulator.link.telemetry.streams import StreamSchedule

    channel = Channel(NullEndpoint(), ("127.0.0.1", 14550), server.sysid, 1, server.counters,
                      StreamSchedule(default_rates(), server.chunk_s))
    sent: list = []
    channel.send = sent.append
    server.channels[("test", 0)] = channel
    return channel, sent
