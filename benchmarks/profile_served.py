"""Where a served rig's time goes at ``--speedup max`` with one UDP client.

Run from the repository root: ``.venv/bin/python -m benchmarks.profile_served [WALL_S] [--airframe NAME]``.

In this process: a :class:`~rig_emulator.link.server.RigServer` on ``udpin:127.0.0.1:0`` at
speed-up 0 (as fast as possible, the serve loop's 20 ms chunks); in a subprocess: the
``served-max`` benchmark's UDP client (``benchmarks.served_max._udp_client``: HEARTBEAT at
1 Hz, every datagram parsed with pymavlink). Each layer of the loop is wrapped with a timer
that keeps **exclusive** wall time and CPU time of this thread (a callee's time is taken off
its caller's), and the table gives calls, wall us and CPU us per **simulated second**:

1. the compiled step loop (numba's entry point: argument unboxing + the physics steps);
2. the Python around it (``LiveRig.step``, ``Simulation._advance``);
3. the per-chunk polls of the server (mission, fences, flight tasks, faults, console);
4. ``LiveRig.snapshot``; 5. ``emit_streams`` and the stream schedules; 6. each message builder;
7. ``Channel.send`` (sequence number, queueing into the datagram); 8. pymavlink's ``pack``
(payload struct) and ``_pack`` (header, CRC, signing); 9. ``sendto``; A. receiving and
handling; B. HEARTBEAT; C. the rest of the loop.

CPU time is the figure to compare on a shared machine (wall time includes being descheduled),
but other processes' load also slows each operation (caches, shared cores): compare runs made
back to back. The timers add ~1 us per wrapped call.
"""

from __future__ import annotations

import argparse
import collections
import os
import signal
import subprocess
import sys
import time
from time import perf_counter as _wall
from time import thread_time as _cpu

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from protocol.dialect import mavlink as M  # noqa: E402
import rig_emulator.simulation.run as run_mod  # noqa: E402
from rig_emulator.config.loader import load_config  # noqa: E402
from rig_emulator.link import server as srv  # noqa: E402
from rig_emulator.link.endpoints import channel as chmod, sockets  # noqa: E402
from rig_emulator.link.serve import chunk_seconds, prepare_rig  # noqa: E402
from rig_emulator.link.telemetry import stream_table  # noqa: E402
from rig_emulator.simulation import entry_points, live  # noqa: E402

acc_w: dict = collections.defaultdict(float)
acc_c: dict = collections.defaultdict(float)
calls: collections.Counter = collections.Counter()
_stack: list = []  # [name, wall0, cpu0, child wall, child cpu]


def timed(name, fn):
    def wrapper(*a, **k):
        _stack.append([name, _wall(), _cpu(), 0.0, 0.0])
        try:
            return fn(*a, **k)
        finally:
            n, w0, c0, cw, cc = _stack.pop()
            dw, dc = _wall() - w0, _cpu() - c0
            acc_w[n] += dw - cw
            acc_c[n] += dc - cc
            calls[n] += 1
            if _stack:
                _stack[-1][3] += dw
                _stack[-1][4] += dc
    return wrapper


def _patch(obj, attr, name):
    setattr(obj, attr, timed(name, getattr(obj, attr)))


def instrument() -> None:
    entry_point = entry_points.entry_point  # BoundEntry looks it up here, once per set of argument objects
    entry_points.entry_point = lambda d, a: (timed("1 compiled step loop (unboxing + steps)", entry_point(d, a))
                                             if d is run_mod.run_steps else entry_point(d, a))
    _patch(run_mod.Simulation, "_advance", "2 Simulation._advance")
    _patch(live.LiveRig, "step", "2 LiveRig.step (supply charge)")
    _patch(srv.RigServer, "step_chunk", "3 step_chunk polls")
    _patch(live.LiveRig, "snapshot", "4 LiveRig.snapshot")
    _patch(srv.RigServer, "emit_streams", "5 emit_streams + schedules")
    for s in stream_table.STREAMS.values():
        object.__setattr__(s, "build", timed(f"6 build {s.name}", s.build))
    _patch(chmod.Channel, "send", "7 Channel.send")
    for cls in M.mavlink_map.values():
        if "pack" in cls.__dict__:
            cls.pack = timed("8 pymavlink pack (payload)", cls.pack)
    M.MAVLink_message._pack = timed("8 pymavlink _pack (header, CRC)", M.MAVLink_message._pack)
    _patch(sockets._Udp, "_send_datagram", "9 sendto")
    _patch(srv.RigServer, "service_io", "A service_io")
    _patch(srv.RigServer, "_heartbeat_if_due", "B heartbeat")
    _patch(srv.RigServer, "run", "C run loop (rest)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("wall_s", nargs="?", type=float, default=8.0, help="wall seconds to profile (default 8)")
    ap.add_argument("--airframe", default="hilms-ideal", help="default: the served-max benchmark's hilms-ideal")
    args = ap.parse_args()
    instrument()
    rig = prepare_rig(load_config(airframe=args.airframe))
    server = srv.RigServer(rig, ["udpin:127.0.0.1:0"], speedup=0.0, chunk_s=chunk_seconds(5.0, 0.0))
    url = server.urls[0]
    client = subprocess.Popen([sys.executable, "-c",
                               "import json; from benchmarks.served_max import _udp_client; "
                               f"r = _udp_client({url!r}, {args.wall_s + 1.0}); r.pop('window'); print(json.dumps(r))"],
                              stdout=subprocess.PIPE, text=True, cwd=ROOT)
    t0 = time.monotonic()
    while not server.channels and time.monotonic() - t0 < 30:
        server.service_io()
        time.sleep(0.01)
    server.step_chunk()
    server.emit_streams()
    server.flush()
    acc_w.clear(), acc_c.clear(), calls.clear()
    sim0 = rig.time_s
    signal.signal(signal.SIGALRM, lambda *_: server.stop())
    signal.setitimer(signal.ITIMER_REAL, args.wall_s)
    w0, c0, load0 = time.monotonic(), time.process_time(), os.getloadavg()[0]
    server.run()
    w1, c1 = time.monotonic(), time.process_time()
    sim = rig.time_s - sim0
    print(f"{args.airframe}: {sim:.2f} simulated s in {w1 - w0:.2f} wall s = {sim / (w1 - w0):.1f}x real time; "
          f"CPU {(c1 - c0) / (w1 - w0):.2f} cores = {(c1 - c0) / sim * 1e3:.2f} ms per simulated s; "
          f"{server.counters.sent / sim:.1f} frames and {server.endpoints[0].datagrams_sent / sim:.1f} datagrams "
          f"per simulated s; load average {load0:.1f}")
    tw, tc = sum(acc_w.values()), sum(acc_c.values())
    print(f"{'layer':45s} {'calls/sim s':>11s} {'wall us/sim s':>13s} {'CPU us/sim s':>12s} {'CPU us/call':>11s}")
    groups: dict = collections.defaultdict(lambda: [0.0, 0.0])
    for n in sorted(acc_w):
        print(f"{n:45s} {calls[n] / sim:11.1f} {acc_w[n] / sim * 1e6:13.0f} {acc_c[n] / sim * 1e6:12.0f} "
              f"{acc_c[n] / calls[n] * 1e6:11.1f}")
        groups[n[:1]][0] += acc_w[n]
        groups[n[:1]][1] += acc_c[n]
    print(f"{'total':45s} {'':11s} {tw / sim * 1e6:13.0f} {tc / sim * 1e6:12.0f}")
    print("by layer: " + ", ".join(f"{k} {c / sim * 1e3:.2f} ms ({c / tc:.0%})" for k, (w, c) in sorted(groups.items())))
    print("client:", client.communicate()[0].strip())
    server.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
