"""Ground-station side of the MAVLink benchmarks: what is measured, with pymavlink, over loopback.

The same functions run against the rig and against the reference responder
(:mod:`benchmarks.mavlink_responder`), so the two figures differ only by the vehicle:

* :func:`command_round_trips` - COMMAND_LONG -> its COMMAND_ACK, one at a time, with a random
  pause before each so that the requests fall at every phase of the rig's 5 ms physics chunks;
* :func:`mission_items` / :func:`mission_round_trip` - upload and download of an N-item
  mission with :class:`rig_emulator.testing.rig.MissionClient` (one request in flight, as
  QGroundControl and MAVSDK do);
* :func:`count_stream` - every message received during a wall-clock window, with the span of
  simulated time the rig's ATTITUDE stamps cover; :func:`drain` - read until the link is quiet;
* :class:`ServedProcess` - a subprocess that prints the URL it serves (the responder).
"""

from __future__ import annotations

import math
import queue
import random
import subprocess
import sys
import threading
import time
from collections import Counter

import numpy as np

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionItem
from rig_emulator.testing.rig import MissionClient, stamp_s

NAN = float("nan")
#: The command timed: a read-only query the rig answers (ACK, then MESSAGE_INTERVAL).
TIMED_COMMAND = M.MAV_CMD_GET_MESSAGE_INTERVAL
TIMED_PARAMS = (float(M.MAVLINK_MSG_ID_ATTITUDE),)


def percentiles_ms(samples_s, prefix: str) -> dict[str, float]:
    """``{prefix}_p50_ms``, ``_p99_ms``, ``_max_ms`` of durations in seconds."""
    x = np.asarray(samples_s, dtype=float) * 1e3
    if x.size == 0:
        raise ValueError(f"{prefix}: no samples")
    p50, p99 = np.percentile(x, [50.0, 99.0])
    return {f"{prefix}_p50_ms": float(p50), f"{prefix}_p99_ms": float(p99), f"{prefix}_max_ms": float(x.max())}


def command_round_trips(conn, n: int, target=(1, 1), max_pause_s: float = 0.005, timeout_s: float = 5.0,
                        seed: int = 0) -> np.ndarray:
    """Seconds from sending each of ``n`` COMMAND_LONG to receiving its COMMAND_ACK."""
    rng = random.Random(seed)
    params = list(TIMED_PARAMS) + [NAN] * (7 - len(TIMED_PARAMS))
    out = np.empty(n)
    for i in range(n):
        time.sleep(rng.uniform(0.0, max_pause_s))
        t0 = time.perf_counter()
        conn.mav.command_long_send(target[0], target[1], TIMED_COMMAND, 0, *params)
        deadline = t0 + timeout_s
        while True:
            m = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=max(deadline - time.perf_counter(), 0.0))
            if m is None:
                raise TimeoutError(f"no COMMAND_ACK within {timeout_s} s (round trip {i})")
            if m.command == TIMED_COMMAND:
                break
        out[i] = time.perf_counter() - t0
        if m.result != M.MAV_RESULT_ACCEPTED:
            raise RuntimeError(f"command {TIMED_COMMAND} answered with result {m.result}")
    return out


def mission_items(n: int, frame: int = M.MAV_FRAME_LOCAL_ENU) -> list[MissionItem]:
    """``n`` NAV_WAYPOINT items on a 2 m circle at 1 m to 3 m altitude (exact in MISSION_ITEM_INT)."""
    items = []
    for k in range(n):
        a = 2.0 * math.pi * k / max(n, 1)
        x = round(2.0 * math.cos(a) * 1e4) / 1e4
        y = round(2.0 * math.sin(a) * 1e4) / 1e4
        z = float(np.float32(1.0 + 2.0 * k / max(n, 1)))
        items.append(MissionItem(seq=k, frame=frame, command=M.MAV_CMD_NAV_WAYPOINT, current=int(k == 0),
                                 x=x, y=y, z=z))
    return items


def mission_round_trip(conn, items, target=(1, 1)) -> dict:
    """Upload ``items``, download them back; seconds of each, items per second, retries, equality."""
    client = MissionClient(conn, target=target)
    t0 = time.perf_counter()
    result = client.upload(items)
    t1 = time.perf_counter()
    if result != M.MAV_MISSION_ACCEPTED:
        raise RuntimeError(f"mission upload of {len(items)} items answered with MISSION_ACK type {result}")
    retries_up = client.retries
    back = client.download()
    t2 = time.perf_counter()
    same = len(back) == len(items) and all(
        (a.seq, a.frame, a.command, a.x, a.y, a.z) == (b.seq, b.frame, b.command, b.x, b.y, b.z)
        for a, b in zip(items, back))
    if not same:
        raise RuntimeError(f"downloaded mission ({len(back)} items) differs from the uploaded one ({len(items)})")
    return {"upload_s": t1 - t0, "download_s": t2 - t1,
            "upload_items_per_s": len(items) / (t1 - t0), "download_items_per_s": len(items) / (t2 - t1),
            "retries_upload": retries_up, "retries_download": client.retries - retries_up}


def count_stream(conn, wall_s: float, clock: str = "ATTITUDE", heartbeat_s: float | None = 1.0) -> dict:
    """Receive for ``wall_s`` wall seconds: messages by type, their total, and the simulated span.

    With ``heartbeat_s`` the client sends a GCS HEARTBEAT at that period, as a ground station
    does. ``sim_span_s`` is the advance of the ``clock`` message's own time stamps.
    """
    counts: Counter = Counter()
    first = last = None
    t_end = time.monotonic() + wall_s
    next_hb = time.monotonic()
    t_start = time.monotonic()
    while True:
        now = time.monotonic()
        if now >= t_end:
            break
        if heartbeat_s is not None and now >= next_hb:
            conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            next_hb += heartbeat_s
        m = conn.recv_match(blocking=True, timeout=min(0.05, max(t_end - now, 0.0)))
        if m is None:
            continue
        kind = m.get_type()
        counts[kind] += 1
        if kind == clock:
            s = stamp_s(m)
            first = s if first is None else first
            last = s
    wall = time.monotonic() - t_start
    return {"counts": dict(counts), "total": sum(counts.values()), "wall_s": wall,
            "sim_span_s": (last - first) if first is not None else 0.0}


def drain(conn, gap_s: float = 0.1, max_s: float = 3.0) -> int:
    """Read and drop messages until none arrives for ``gap_s`` (at most ``max_s``); returns how many."""
    n = 0
    deadline = time.monotonic() + max_s
    while time.monotonic() < deadline:
        if conn.recv_match(blocking=True, timeout=gap_s) is None:
            break
        n += 1
    return n


class ServedProcess:
    """``python -m MODULE`` in a subprocess that prints ``PREFIX URL`` once it serves."""

    def __init__(self, module: str, prefix: str, args=(), start_timeout_s: float = 60.0):
        self.proc = subprocess.Popen([sys.executable, "-m", module, *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        lines: queue.Queue = queue.Queue()

        def pump():
            for line in self.proc.stdout:
                lines.put(line.strip())
            lines.put(None)

        threading.Thread(target=pump, daemon=True).start()
        deadline = time.monotonic() + start_timeout_s
        self.url = None
        while self.url is None:
            try:
                line = lines.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                self.stop()
                raise RuntimeError(f"{module} did not start within {start_timeout_s} s") from None
            if line is None:
                raise RuntimeError(f"{module} exited with {self.proc.wait()}: {self.proc.stderr.read()}")
            if line.startswith(prefix):
                self.url = line[len(prefix):]

    @property
    def pid(self) -> int:
        return self.proc.pid

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
