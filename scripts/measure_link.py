"""Measure the MAVLink rig from a pymavlink client on loopback (figures quoted in the issue notes).

Run from the repository root: ``.venv/bin/python scripts/measure_link.py``. Prints telemetry
messages per simulated second at speed-up 1, COMMAND_LONG -> COMMAND_ACK latency (p50, p99,
max over 300 round trips) and the real-time factor of ``--speedup max`` with one client.
Issue 8 will fold these into ``python -m benchmarks``.
"""
import time
from rig_emulator.link.testing import RigProcess, collect, connect, recv, stamp_s
# 1) telemetry msgs/s at speedup 1 + command latency
with RigProcess(speedup=1.0) as rig:
    c = connect(rig.tcp_url)
    recv(c, "ATTITUDE")
    got = collect(c, sim_seconds=10.0)
    n = sum(len(v) for v in got.values())
    att = sorted(stamp_s(m) for m in got["ATTITUDE"])
    print(f"speedup 1: {n} messages over {att[-1]-att[0]:.2f} sim s -> {n/(att[-1]-att[0]):.1f} msg/s; ATTITUDE {len(att)/(att[-1]-att[0]):.2f} Hz")
    lat = []
    for i in range(300):
        t = time.perf_counter()
        c.mav.command_long_send(1, 1, 31999, 0, *[float('nan')]*7)
        a = recv(c, "COMMAND_ACK")
        lat.append((time.perf_counter()-t)*1000)
    lat.sort()
    print(f"COMMAND_LONG->ACK ms: p50 {lat[len(lat)//2]:.3f} p99 {lat[int(len(lat)*0.99)]:.3f} max {lat[-1]:.3f}")
    c.close(); rig.stop()
# 2) RTF at max with one client
with RigProcess(speedup="max") as rig:
    c = connect(rig.tcp_url)
    recv(c, "ATTITUDE")
    t0 = time.monotonic(); first = None; last = None; n = 0
    while time.monotonic() - t0 < 10:
        m = c.recv_match(blocking=True, timeout=0.5)
        if m is None: continue
        n += 1
        if m.get_type() == "ATTITUDE":
            s = stamp_s(m)
            if first is None: first = (s, time.monotonic())
            last = (s, time.monotonic())
    print(f"speedup max, one client: {last[0]-first[0]:.1f} sim s in {last[1]-first[1]:.2f} wall s -> RTF {(last[0]-first[0])/(last[1]-first[1]):.1f}; client decoded {n} msgs")
    c.close(); rig.stop()
