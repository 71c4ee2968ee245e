"""memory: resident memory of the rig, read from /proc (VmRSS, VmHWM).

Probes (each a fresh process; the numba cache is warm, so no process here compiles):

* ``mem-rig`` - ``rig-emulator serve --speedup 1``: **idle** (serving MAVLink on TCP, no
  client has ever connected) ``idle_s`` seconds after it started serving; then **flying**: a
  pymavlink client attaches, receives the default streams, uploads a 20-waypoint mission,
  arms and starts it (MAV_CMD_MISSION_START), and after ``fly_s`` seconds of flight the
  rig's RSS is read again (and once in between, to see whether it grows). The rig's peak
  (VmHWM) over its life is reported too.
* ``mem-headless-250s`` - ``rig_emulator.api.simulate("helix", duration=250)`` (Fig. 17's
  250 s run) in the probe process: the peak RSS during the run (VmHWM restarted just
  before it with ``/proc/self/clear_refs``), the RSS before it (imports, cache load and a
  1 s warm-up run done), and the size of the result's time series.
* ``mem-floor`` - the reference: a fresh Python that imports numpy and pymavlink with the
  hilms dialect (what any MAVLink tool in Python holds), then numba and scipy (the rig's
  other run-time dependencies); RSS after each.

RotorPy's 250 s run is not measured: at RotorPy's ~0.6x real time it would take about seven
minutes per repetition.
"""

from __future__ import annotations

import time

from . import procfs
from .harness import Metric, ProbeStats, benchmark, paired_ratio_metric, probe
from .link_client import count_stream, mission_items
from .served_rig import ServedRig, ensure_compiled

RIG_PROBE = "mem-rig"
HEADLESS_PROBE = "mem-headless-250s"
FLOOR_PROBE = "mem-floor"
CACHE_GROUP = "served-rig"
MIB = 1024.0


def _mib(kib: int) -> float:
    return kib / MIB


@probe(RIG_PROBE, params={"idle_s": 3.0, "fly_s": 20.0}, quick={"idle_s": 1.0, "fly_s": 2.0}, cache=CACHE_GROUP,
       description="served rig at speed-up 1: RSS idle (no client), then flying a mission with a client")
def mem_rig_probe(idle_s: float, fly_s: float, warm_up: bool = True) -> dict:
    """RSS of the served rig idle and flying; see the module docstring."""
    from protocol.dialect import mavlink as M
    from rig_emulator.testing.rig import MissionClient, command, connect, recv

    figs: dict = {"warmup_s": ensure_compiled() if warm_up else 0.0}
    with ServedRig(speedup=1.0, timing=False) as rig:
        time.sleep(idle_s)
        idle = procfs.memory_kib(rig.pid)
        figs["idle_rss_mib"] = _mib(idle["rss"])
        figs["startup_hwm_mib"] = _mib(idle["hwm"])

        conn = connect(rig.tcp_url)
        if recv(conn, "ATTITUDE", timeout=30.0) is None:
            raise RuntimeError("the rig sent no ATTITUDE within 30 s")
        if MissionClient(conn).upload(mission_items(20)) != M.MAV_MISSION_ACCEPTED:
            raise RuntimeError("the rig refused the mission")
        for cmd, params in ((M.MAV_CMD_COMPONENT_ARM_DISARM, (1,)), (M.MAV_CMD_MISSION_START, (0, 0))):
            ack = command(conn, cmd, *params)
            if ack is None or ack.result != M.MAV_RESULT_ACCEPTED:
                raise RuntimeError(f"command {cmd} not accepted: {ack}")
        if recv(conn, "MISSION_CURRENT", timeout=10.0,
                condition=lambda m: m.mission_state == M.MISSION_STATE_ACTIVE) is None:
            raise RuntimeError("the mission did not become active")
        first = count_stream(conn, fly_s / 2)
        mid = procfs.memory_kib(rig.pid)
        second = count_stream(conn, fly_s / 2)
        end = procfs.memory_kib(rig.pid)
        pos = recv(conn, "LOCAL_POSITION_NED", timeout=5.0)
        conn.close()
    figs["flying_rss_mib"] = _mib(end["rss"])
    figs["flying_rss_growth_mib_per_min"] = _mib(end["rss"] - mid["rss"]) / (second["wall_s"] / 60.0)
    figs["lifetime_hwm_mib"] = _mib(end["hwm"])
    figs["flight_msgs_received"] = first["total"] + second["total"]
    if pos is not None:
        figs["final_altitude_m"] = -float(pos.z)  # the mission climbs to 1-3 m: the rig flew
    return figs


@probe(HEADLESS_PROBE, params={"duration": 250.0}, quick={"duration": 10.0}, cache=CACHE_GROUP,
       description="rig_emulator.api.simulate('helix', duration=250): peak RSS during the run")
def mem_headless_probe(duration: float) -> dict:
    """Peak RSS of a headless helix run of ``duration`` simulated seconds."""
    from rig_emulator.api import simulate

    simulate("helix", duration=1.0, seed=0)  # loads (or compiles) the step loop
    before = procfs.memory_kib()
    if not procfs.reset_peak():
        raise RuntimeError("cannot reset VmHWM (/proc/self/clear_refs): the peak would include start-up")
    t0 = time.perf_counter()
    result = simulate("helix", duration=duration, seed=0)
    wall = time.perf_counter() - t0
    after = procfs.memory_kib()
    series_bytes = sum(getattr(v, "nbytes", 0) for v in result.series.values())
    return {
        "rss_before_mib": _mib(before["rss"]),
        "run_peak_mib": _mib(after["hwm"]),
        "run_increment_mib": _mib(after["hwm"] - before["rss"]),
        "rss_after_mib": _mib(after["rss"]),
        "series_mib": series_bytes / MIB / MIB,
        "sim_time_s": float(result.sim_time_s),
        "wall_s": wall,
    }


_FLOOR_SCRIPT = """
import json, sys
sys.path[:0] = json.loads(sys.argv[1])
def rss():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
out = {"python_rss_mib": rss()}
import numpy
from pymavlink import mavutil
from protocol.dialect import use_hilms_dialect
use_hilms_dialect()
out["numpy_pymavlink_rss_mib"] = rss()
import numba, scipy.linalg
out["with_numba_scipy_rss_mib"] = rss()
print(json.dumps(out))
"""


@probe(FLOOR_PROBE, params={}, description="fresh Python importing numpy + pymavlink (+ dialect), then numba + scipy")
def mem_floor_probe() -> dict:
    """RSS of the imports every rig process needs, stage by stage, in a clean interpreter.

    (The probe's own process has imported the benchmark modules already, so the figures come
    from a child ``python -c`` that imports nothing else.)
    """
    import json
    import subprocess
    import sys

    from .harness import REPO_ROOT

    proc = subprocess.run([sys.executable, "-c", _FLOOR_SCRIPT, json.dumps([str(REPO_ROOT)])],
                          capture_output=True, text=True, timeout=120, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


@benchmark("memory", probes=(RIG_PROBE, HEADLESS_PROBE, FLOOR_PROBE),
           description="resident memory of an idle and a flying served rig, peak of the 250 s headless run; "
                       "vs a Python holding numpy + pymavlink")
def memory(stats: dict[str, ProbeStats]) -> list[Metric]:
    rig, run, floor = stats[RIG_PROBE], stats[HEADLESS_PROBE], stats[FLOOR_PROBE]
    ref_key = "numpy_pymavlink_rss_mib"
    return [
        rig.metric("idle_rss_mib", "served rig, idle (no client): RSS", "MiB"),
        rig.metric("flying_rss_mib", "served rig, flying a mission with a client: RSS", "MiB"),
        rig.metric("flying_rss_growth_mib_per_min", "served rig, flying: RSS growth", "MiB/min",
                   note="over the second half of the flight; ~0 means no leak on this time scale"),
        rig.metric("lifetime_hwm_mib", "served rig: peak RSS over its life", "MiB"),
        run.metric("run_peak_mib", "headless helix run: peak RSS", "MiB",
                   note="VmHWM restarted just before simulate(): start-up and cache load excluded"),
        run.metric("rss_before_mib", "headless: RSS before the run (imports, cache loaded)", "MiB"),
        run.metric("run_increment_mib", "headless: peak above the RSS before the run", "MiB"),
        run.metric("series_mib", "headless: the result's time series", "MiB"),
        floor.metric(ref_key, "reference: python + numpy + pymavlink (hilms dialect)", "MiB"),
        floor.metric("with_numba_scipy_rss_mib", "reference: ... + numba + scipy", "MiB"),
        paired_ratio_metric(rig, "idle_rss_mib", floor, ref_key, "idle rig RSS vs reference"),
        paired_ratio_metric(rig, "flying_rss_mib", floor, ref_key, "flying rig RSS vs reference"),
        paired_ratio_metric(run, "run_peak_mib", floor, ref_key, "headless 250 s peak vs reference"),
        paired_ratio_metric(rig, "idle_rss_mib", floor, "with_numba_scipy_rss_mib",
                            "idle rig RSS vs reference with numba + scipy"),
    ]
