"""jitter: wall-clock regularity of the served rig's control loop at speed-up 1.

What is measured. The served rig advances its physics and controllers in chunks of 5 ms of
simulated time, each paced against the wall clock (see
:mod:`rig_emulator.link.loop_timing`): inside a chunk the controller runs at its fixed
simulated rate (500 Hz; in simulated time its period has no jitter at all), and on the wall
clock the chunk is when its outputs come into being and its telemetry leaves. So the
control loop's wall-clock period is the spacing of consecutive chunk starts, nominally
5 ms. The rig records every chunk (``--timing-log``); the probe reports, over the window a
ground station was attached:

* **period error** ``|start[k] - start[k-1] - 5 ms|`` p50 / p99 / max (target: p99 < 1 ms);
* **lateness** ``start - due`` against the pacing schedule, p50 / p99 / max, and the fraction
  of chunks more than 1 ms late;
* **busy time** per chunk (step + telemetry + socket writes), p50 / p99 / max;
* simulated seconds per wall second (1 = the control rate held), rig CPU use.

Conditions: ``rig-emulator serve --speedup 1`` (fresh process, numba cache warm) with one
pymavlink ground station on TCP loopback that receives every stream at its default rate
and sends HEARTBEAT at 1 Hz, for ``duration_s`` wall seconds (the first 0.5 s after it
attached are skipped).

Reference (``jitter-pacer``): the same pacing loop with no work in it - ``select()`` on a
listening socket until the next 5 ms boundary, recorded with the same ``LoopTiming`` and
summarised by the same function - in a fresh process right after the rig's, for the same
duration: the floor that Python, the kernel and the machine's current load give a 5 ms
loop. The rig's figures are reported next to it, as ratios and as the excess in ms.
"""

from __future__ import annotations

import select
import socket
import time

from . import procfs
from .harness import (
    Metric,
    ProbeStats,
    Target,
    benchmark,
    paired_difference_metric,
    paired_ratio_metric,
    probe,
)
from .link_client import count_stream
from .served_rig import ServedRig, ensure_compiled

RIG_PROBE = "jitter-rig"
PACER_PROBE = "jitter-pacer"
CACHE_GROUP = "served-rig"
CHUNK_S = 0.005  # the serve loop's chunk at speed-up 1 (--chunk-ms default)
SETTLE_S = 0.5
JITTER_TARGET = Target("<=", 1.0, "the control period within 1 ms")


@probe(RIG_PROBE, params={"duration_s": 30.0}, quick={"duration_s": 2.0}, cache=CACHE_GROUP,
       description="served rig at speed-up 1 with a ground station at default stream rates: chunk timing")
def jitter_rig_probe(duration_s: float, warm_up: bool = True) -> dict:
    """Chunk period error, lateness and busy time of the served rig; see the module docstring."""
    from rig_emulator.link.loop_timing import summarize
    from rig_emulator.testing.rig import connect, recv

    figs: dict = {"warmup_s": ensure_compiled() if warm_up else 0.0}
    load = procfs.MachineLoad()
    with ServedRig(speedup=1.0) as rig:
        conn = connect(rig.tcp_url)
        if recv(conn, "ATTITUDE", timeout=30.0) is None:
            raise RuntimeError("the rig sent no ATTITUDE within 30 s")
        count_stream(conn, SETTLE_S)
        load.start()
        cpu0, t0 = procfs.cpu_seconds(rig.pid), time.monotonic()
        stream = count_stream(conn, duration_s)
        cpu1, t1 = procfs.cpu_seconds(rig.pid), time.monotonic()
        load.stop()
        conn.close()
        rig.stop()
        timing = rig.timing()
    figs.update(summarize(timing, t0, t1))
    figs["reanchors"] = timing["reanchors"]
    figs["rig_cpu_fraction"] = (cpu1 - cpu0) / (t1 - t0)
    figs["client_msgs_per_wall_s"] = stream["total"] / stream["wall_s"]
    figs.update(load.figures())
    return figs


def pace(duration_s: float, chunk_s: float = CHUNK_S, speedup: float = 1.0):
    """The serve loop's pacing with no work: a :class:`LoopTiming` of ``duration_s`` of chunks."""
    from rig_emulator.link.loop_timing import LoopTiming

    timing = LoopTiming(chunk_s, speedup, capacity=int(duration_s / chunk_s * speedup) + 16)
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        wall0 = time.monotonic()
        sim0 = sim = 0.0
        while sim < duration_s:
            t0 = time.monotonic()
            lag = sim0 + (t0 - wall0) * speedup - sim
            if lag < chunk_s:
                select.select([sock], [], [], (chunk_s - lag) / speedup)
                continue
            start = time.monotonic()
            due = wall0 + (sim + chunk_s - sim0) / speedup
            sim += chunk_s
            timing.record(due, start, time.monotonic(), sim - chunk_s)
    finally:
        sock.close()
    return timing


@probe(PACER_PROBE, params={"duration_s": 30.0}, quick={"duration_s": 2.0},
       description="the serve loop's 5 ms pacing with no work in it (the floor)")
def jitter_pacer_probe(duration_s: float) -> dict:
    """Period error and lateness of an empty 5 ms paced loop."""
    from rig_emulator.link.loop_timing import summarize

    load = procfs.MachineLoad().start()
    cpu0 = time.process_time()
    timing = pace(duration_s)
    cpu = time.process_time() - cpu0
    load.stop()
    arrays = timing.arrays()
    log = {**arrays, "chunk_s": timing.chunk_s, "speedup": timing.speedup}
    figs = summarize(log, arrays["start"][0] + SETTLE_S)
    figs["cpu_fraction"] = cpu / duration_s
    figs.update(load.figures())
    return figs


@benchmark("jitter", probes=(RIG_PROBE, PACER_PROBE),
           description="control-loop (chunk) period jitter at speed-up 1 with a ground station attached; "
                       "vs an empty paced loop")
def jitter(stats: dict[str, ProbeStats]) -> list[Metric]:
    rig, pacer = stats[RIG_PROBE], stats[PACER_PROBE]
    out = [
        rig.metric("period_err_p99_ms", "chunk period error p99", "ms", targets=(JITTER_TARGET,),
                   note="|spacing of consecutive chunk starts - 5 ms|; the controller's wall-clock period"),
        rig.metric("period_err_p50_ms", "chunk period error p50", "ms"),
        rig.metric("period_err_max_ms", "chunk period error max", "ms"),
        rig.metric("lateness_p99_ms", "chunk lateness p99", "ms",
                   note="chunk start - its scheduled instant"),
        rig.metric("lateness_p50_ms", "chunk lateness p50", "ms"),
        rig.metric("lateness_max_ms", "chunk lateness max", "ms"),
        rig.metric("late_over_1ms_fraction", "chunks more than 1 ms late", "fraction"),
        rig.metric("busy_p50_ms", "chunk busy time p50", "ms", note="step + telemetry + socket writes"),
        rig.metric("busy_p99_ms", "chunk busy time p99", "ms"),
        rig.metric("sim_per_wall", "simulated s per wall s", "x",
                   targets=(Target(">=", 0.99, "control rate held"),)),
        rig.metric("rig_cpu_fraction", "rig CPU use", "cores"),
        rig.metric("client_msgs_per_wall_s", "messages the ground station received", "msg/s"),
        pacer.metric("period_err_p99_ms", "reference: empty loop period error p99", "ms"),
        pacer.metric("lateness_p99_ms", "reference: empty loop lateness p99", "ms"),
        paired_ratio_metric(rig, "period_err_p99_ms", pacer, "period_err_p99_ms", "period error p99 vs empty loop"),
        paired_difference_metric(rig, "period_err_p99_ms", pacer, "period_err_p99_ms",
                                 "period error p99 above empty loop", "ms",
                                 note="what the rig's work adds to the machine's floor (paired by repetition)"),
        paired_difference_metric(rig, "lateness_p99_ms", pacer, "lateness_p99_ms",
                                 "lateness p99 above empty loop", "ms"),
        rig.metric("machine_busy_cores", "machine load during the rig window (all processes)", "cores"),
        pacer.metric("machine_busy_cores", "machine load during the reference window", "cores"),
    ]
    return out
