"""Fuzz a running rig over real sockets and check it afterwards (``benchmarks/fuzz_link.py``, tests).

:func:`fuzz_rig` talks to a rig process (:class:`~rig_emulator.testing.rig.RigProcess`) that
serves a ``tcpin`` and a ``udpin`` endpoint:

1. a control client on TCP reads the rig's counters (:mod:`rig_emulator.link.telemetry.link_status`),
   its physics and control rates (parameters ``SIM_PHYS_HZ``, ``SIM_CTRL_HZ``) and ATTITUDE's
   simulated-time stamps for a baseline;
2. ``frames`` datagrams of :class:`~rig_emulator.testing.fuzz.FrameFactory` go to the UDP
   endpoint from one socket, in windows of ``window`` datagrams: after each window the control
   client asks for the counters until the rig has read every byte sent (so the kernel never
   drops a datagram for a full socket buffer and the counts can be compared exactly); optionally
   ``tcp_frames`` more go down a second TCP connection as one byte stream;
3. afterwards: the process is alive, ACKs a command, answers a parameter read; every counter
   the oracle predicts (:func:`~rig_emulator.testing.fuzz.expected_counts`) matches, no
   handler raised, and the simulated time advanced as the step counter says.

Rates (simulated seconds per wall second before, during and after the flood, from the
counters' time stamps and from ATTITUDE's) are reported, not asserted: speed is measured by
scripts, never by tests.
"""

from __future__ import annotations

import os
import socket
import time
from collections import Counter
from dataclasses import dataclass, field

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry.link_status import DROP_NAMES, read_link_status
from rig_emulator.testing.rig import command, connect, recv, stamp_s
from rig_emulator.testing.fuzz import FrameFactory, StreamOracle, expected_counts

#: counters the oracle predicts exactly, by LinkCounters name -> NAMED_VALUE_INT name
EXACT = {"received": "RX_MSGS", "rx_bytes": "RX_BYTES", "bad_bytes": "BAD_BYTES",
         **{k: DROP_NAMES[k] for k in ("bad_crc", "bad_prefix", "bad_data", "truncated", "unknown_id", "own_echo",
                                       "other_system", "other_component", "unhandled")}}


@dataclass
class Sample:
    wall: float
    status: dict


@dataclass
class FuzzResult:
    frames: int = 0
    fuzz_bytes: int = 0
    kinds: Counter = field(default_factory=Counter)
    tcp_frames: int = 0
    expected: Counter = field(default_factory=Counter)
    observed: dict = field(default_factory=dict)
    mismatches: dict = field(default_factory=dict)
    fuzz_wall_s: float = 0.0
    physics_hz: float = 0.0
    control_hz: float = 0.0
    rate_before: float = 0.0  # simulated s per wall s, from the counters' stamps
    rate_during: float = 0.0
    rate_after: float = 0.0
    attitude_rate_during: float = 0.0  # the same from ATTITUDE stamps on the control link
    rig_cpu_during: float = float("nan")  # the rig process's CPU time / wall time during the flood
    host_load: tuple = ()  # /proc/loadavg at the end of the flood
    pacing_resets: int = 0  # during the flood
    lag_ms: int = 0
    steps: int = 0  # physics steps during the flood
    control_steps: int = 0
    step_time_error_s: float = 0.0  # |steps / physics_hz - simulated time| at the end
    alive: bool = False
    command_ack: int | None = None
    param_answer: float | None = None
    handler_errors: int = 0
    dropped_total: int = 0
    final: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return (self.alive and self.command_ack == M.MAV_RESULT_ACCEPTED and self.param_answer is not None
                and not self.mismatches and self.handler_errors == 0 and self.step_time_error_s < 0.0025)

    def report(self) -> str:
        lines = [
            f"frames sent: {self.frames} UDP datagrams ({self.fuzz_bytes} bytes) + {self.tcp_frames} frames on TCP "
            f"in {self.fuzz_wall_s:.1f} s ({(self.frames + self.tcp_frames) / max(self.fuzz_wall_s, 1e-9):.0f} frames/s)",
            "kinds: " + ", ".join(f"{k} {n}" for k, n in sorted(self.kinds.items())),
            "rig counted (delta over the flood): " + ", ".join(f"{k} {v}" for k, v in self.observed.items()),
            "oracle: " + ", ".join(f"{k} {self.expected.get(k, 0)}" for k in EXACT),
            f"counter mismatches: {self.mismatches or 'none'}; handler errors: {self.handler_errors}; "
            f"dropped in all (rig total): {self.dropped_total}",
            f"physics {self.physics_hz:g} Hz, control {self.control_hz:g} Hz; simulated s per wall s: "
            f"before {self.rate_before:.4f}, during {self.rate_during:.4f} (ATTITUDE stamps {self.attitude_rate_during:.4f}), "
            f"after {self.rate_after:.4f}",
            f"rig process CPU during the flood: {self.rig_cpu_during:.0%} of one core; host load average {self.host_load}",
            f"during the flood: {self.steps} physics steps, {self.control_steps} control steps "
            f"({self.control_steps / max(self.fuzz_wall_s, 1e-9):.1f} per wall s), pacing resets {self.pacing_resets}, "
            f"lag given up {self.lag_ms} ms",
            f"steps vs simulated time at the end: |STEPS / {self.physics_hz:g} Hz - t| = {self.step_time_error_s * 1e3:.2f} ms",
            f"after: process alive {self.alive}, COMMAND_ACK result {self.command_ack}, PARAM_VALUE SIM_PHYS_HZ = "
            f"{self.param_answer}",
        ]
        return "\n".join(lines)


class _Control:
    """The TCP control client: counter reads (each one COMMAND_LONG the rig counts) and ATTITUDE stamps."""

    def __init__(self, url: str):
        self.conn = connect(url)
        self.sent_msgs = 0
        self.attitude: list[tuple[float, float]] = []  # (wall, simulated) of ATTITUDE

    def _note(self, msg) -> None:
        if msg is not None and msg.get_type() == "ATTITUDE":
            self.attitude.append((time.monotonic(), stamp_s(msg)))

    def drain(self) -> None:
        while True:
            msg = self.conn.recv_match(blocking=False)
            if msg is None:
                return
            self._note(msg)

    def status(self) -> Sample:
        for _ in range(3):
            self.sent_msgs += 1
            got = read_link_status(self.conn, timeout=5.0)
            if got is not None:
                return Sample(time.monotonic(), got)
        raise RuntimeError("the rig did not answer a counter request")

    def bytes_sent(self) -> int:
        return self.conn.mav.total_bytes_sent


def _cpu_s(proc) -> float:
    """User + system CPU seconds of a child process (Linux /proc), NaN when unknown."""
    try:
        with open(f"/proc/{proc.pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (AttributeError, OSError, ValueError, IndexError):
        return float("nan")


def _loadavg() -> tuple:
    try:
        with open("/proc/loadavg") as f:
            return tuple(float(v) for v in f.read().split()[:3])
    except OSError:
        return ()


def _rate(a: Sample, b: Sample) -> float:
    return (b.status["time_s"] - a.status["time_s"]) / max(b.wall - a.wall, 1e-9)


def _attitude_rate(samples, t0: float, t1: float) -> float:
    inside = [(w, s) for w, s in samples if t0 <= w <= t1]
    if len(inside) < 2:
        return float("nan")
    (w0, s0), (w1, s1) = inside[0], inside[-1]
    return (s1 - s0) / max(w1 - w0, 1e-9)


def _param(conn, name: bytes, timeout: float = 5.0):
    conn.mav.param_request_read_send(1, 1, name, -1)
    msg = recv(conn, "PARAM_VALUE", timeout, lambda m: m.param_id == name.decode())
    return None if msg is None else msg.param_value


def fuzz_rig(tcp_url: str, udp_url: str, frames: int, seed: int = 1, window: int = 100, baseline_s: float = 2.0,
             tcp_frames: int = 0, progress=None, proc=None) -> FuzzResult:
    """Flood the rig at ``udp_url`` (a ``udpin:HOST:PORT`` rig URL) and check it over ``tcp_url``."""
    res = FuzzResult(frames=frames, tcp_frames=tcp_frames)
    ctl = _Control(tcp_url)
    try:
        if recv(ctl.conn, "ATTITUDE", 30.0) is None:
            raise RuntimeError("no telemetry from the rig")
        res.physics_hz = _param(ctl.conn, b"SIM_PHYS_HZ") or float("nan")
        res.control_hz = _param(ctl.conn, b"SIM_CTRL_HZ") or float("nan")
        first = ctl.status()
        t_end = time.monotonic() + baseline_s
        while time.monotonic() < t_end:
            ctl._note(ctl.conn.recv_match(blocking=True, timeout=0.1))
        before = ctl.status()  # counts its own request: control traffic is counted from here on
        res.rate_before = _rate(first, before)
        ctl_bytes0, ctl_msgs0 = ctl.bytes_sent(), ctl.sent_msgs
        factory = FrameFactory(seed)
        expected = Counter()
        t0 = time.monotonic()
        cpu0 = _cpu_s(proc)
        sent = _udp_phase(ctl, before, udp_url, factory, frames, window, expected, res, ctl_bytes0, progress)
        if tcp_frames:
            _tcp_phase(ctl, before, tcp_url, factory, tcp_frames, expected, res, sent, ctl_bytes0)
        res.fuzz_wall_s = time.monotonic() - t0
        res.rig_cpu_during = (_cpu_s(proc) - cpu0) / res.fuzz_wall_s
        res.host_load = _loadavg()
        during = ctl.status()
        ctl_msgs, ctl_bytes = ctl.sent_msgs - ctl_msgs0, ctl.bytes_sent() - ctl_bytes0  # all counted by `during`
        res.rate_during = _rate(before, during)
        res.attitude_rate_during = _attitude_rate(ctl.attitude, before.wall, during.wall)
        t_end = time.monotonic() + baseline_s
        while time.monotonic() < t_end:
            ctl._note(ctl.conn.recv_match(blocking=True, timeout=0.1))
        after = ctl.status()
        res.rate_after = _rate(during, after)
        expected["received"] += ctl_msgs
        expected["rx_bytes"] += ctl_bytes
        res.expected = expected
        _compare(res, before.status, during.status, expected)
        d = {k: during.status[k] - before.status[k] for k in ("STEPS", "CTRL_STEPS", "PACE_RESET", "LAG_MS")}
        res.steps, res.control_steps, res.pacing_resets, res.lag_ms = (d["STEPS"], d["CTRL_STEPS"], d["PACE_RESET"],
                                                                      d["LAG_MS"])
        res.handler_errors = after.status["D_HANDLER"]
        res.dropped_total = after.status["DROPPED"]
        res.step_time_error_s = abs(after.status["STEPS"] / res.physics_hz - after.status["time_s"])
        res.final = after.status
        ack = command(ctl.conn, M.MAV_CMD_REQUEST_MESSAGE, float(M.MAVLINK_MSG_ID_AUTOPILOT_VERSION), timeout=5.0)
        res.command_ack = None if ack is None else ack.result
        res.param_answer = _param(ctl.conn, b"SIM_PHYS_HZ")
        res.alive = proc is None or proc.poll() is None
    finally:
        ctl.conn.close()
    return res


def _udp_phase(ctl, before, udp_url, factory, frames, window, expected, res, ctl_bytes0, progress) -> int:
    _, host, port = udp_url.split(":")
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    sent = 0
    try:
        for i in range(frames):
            kind, data = factory.datagram()
            res.kinds[kind] += 1
            expected.update(expected_counts(data))
            while True:
                try:
                    sock.sendto(data, (host, int(port)))
                    break
                except BlockingIOError:
                    time.sleep(0.001)
            sent += len(data)
            if (i + 1) % window == 0 or i + 1 == frames:
                _drain_udp(sock)
                ctl.drain()
                _wait_read(ctl, before, sent, ctl_bytes0, sock)
                if progress is not None:
                    progress(i + 1, frames)
    finally:
        sock.close()
    res.fuzz_bytes = sent
    return sent


def _wait_read(ctl: _Control, before: Sample, fuzz_bytes: int, ctl_bytes0: int, sock=None) -> None:
    """Ask for the counters until the rig has read ``fuzz_bytes`` fuzz bytes and every control
    byte since ``before`` (each request's own bytes are read by the time the rig answers)."""
    deadline = time.monotonic() + 30.0
    while True:
        now = ctl.status()
        missing = fuzz_bytes + ctl.bytes_sent() - ctl_bytes0 - (now.status["RX_BYTES"] - before.status["RX_BYTES"])
        if missing <= 0:
            return
        if time.monotonic() > deadline:
            raise RuntimeError(f"the rig has not read {missing} of the bytes sent to it (lost in a full socket "
                               f"buffer? use a smaller window)")
        if sock is not None:
            _drain_udp(sock)
        time.sleep(0.002)


def _drain_udp(sock) -> None:
    while True:
        try:
            sock.recvfrom(65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:  # ICMP errors and the like
            continue


def _drain_tcp(s) -> None:
    try:
        while s.recv(65536):
            pass
    except (BlockingIOError, InterruptedError):
        pass


def _tcp_phase(ctl, before, tcp_url, factory, n, expected, res, udp_bytes: int, ctl_bytes0: int) -> None:
    """``n`` frames down a second TCP connection as one byte stream (the StreamOracle's counts)."""
    _, host, port = tcp_url.split(":")
    oracle = StreamOracle()
    with socket.create_connection((host, int(port)), timeout=10.0) as s:
        s.setblocking(False)
        for _ in range(n):
            kind, data = factory.datagram()
            res.kinds[f"tcp:{kind}"] += 1
            oracle.feed(data)
            view = memoryview(data)
            while view:
                try:
                    view = view[s.send(view):]
                except BlockingIOError:
                    _drain_tcp(s)
                    time.sleep(0.001)
            _drain_tcp(s)
        got, pending = oracle.counts()
        _wait_read(ctl, before, udp_bytes + got["rx_bytes"], ctl_bytes0)  # all read before we close
        _drain_tcp(s)
    res.kinds["tcp:pending_bytes"] = pending
    expected.update(got)


def _compare(res: FuzzResult, before: dict, during: dict, expected: Counter) -> None:
    for key, name in EXACT.items():
        got = during[name] - before[name]
        res.observed[key] = got
        want = expected.get(key, 0)
        if key == "bad_prefix" and res.tcp_frames:  # the TCP part is a lower bound (StreamOracle)
            if got < want:
                res.mismatches[key] = (f">= {want}", got)
            continue
        if got != want:
            res.mismatches[key] = (want, got)
