"""mavlink-link: the rig's MAVLink link at speed-up 1 over loopback.

Probe ``link-rig`` starts ``rig-emulator serve --speedup 1`` (a fresh process, numba cache
warm, chunk timing log on) and drives it from a pymavlink client in the probe process,
which sends a GCS HEARTBEAT at 1 Hz and reads everything the rig sends:

1. **telemetry at the default stream rates** for ``telemetry_s`` wall seconds: messages
   per wall second and per simulated second, the ATTITUDE rate against its configured
   25 Hz, and whether the rig held its control rate meanwhile (simulated seconds per wall
   second from its chunk record, pacing re-anchors);
2. **command round trips** with the streams on: ``commands`` COMMAND_LONG
   (MAV_CMD_GET_MESSAGE_INTERVAL) -> COMMAND_ACK, p50 / p99 / max;
3. **mission upload and download** of ``mission_items`` NAV_WAYPOINT items with the streams
   on (``MissionClient``: one request in flight), items per second each way;
4. **telemetry at the maximum rate**: every stream requested at 200 Hz (REQUEST_DATA_STREAM
   ALL; the rig caps a stream at one message per 5 ms chunk), for ``stress_s`` seconds:
   messages per wall second with the control rate still checked;
5. the command round trips and the mission transfer again with **every stream off**, the
   conditions of the reference;
6. a second rig at ``--speedup max`` with the same client attached (default streams) for
   ``max_s`` seconds: its real-time factor over the link (simulated s per wall s from its
   chunk record), the figure ``python -m benchmarks --only mavlink-link,jitter`` used to print.

Probe ``link-reference`` measures 2 and 3 against :mod:`benchmarks.mavlink_responder`, a
minimal pymavlink vehicle that only answers (no simulation, no streams), with the same
client code: the floor of this client and pymavlink over this loopback. The benchmark
reports the rig's figures and their ratios to the reference of the same repetition.

No ArduPilot or PX4 SITL is available here, so no autopilot figure is compared.
"""

from __future__ import annotations

import time

from protocol.dialect import mavlink as M

from . import procfs
from .harness import Metric, ProbeStats, Target, benchmark, paired_ratio_metric, probe
from .link_client import (
    ServedProcess,
    command_round_trips,
    count_stream,
    drain,
    mission_items as make_mission_items,
    mission_round_trip,
    percentiles_ms,
)
from .mavlink_responder import PREFIX as RESPONDER_PREFIX
from .served_rig import ServedRig, ensure_compiled

RIG_PROBE = "link-rig"
REFERENCE_PROBE = "link-reference"
CACHE_GROUP = "served-rig"
STRESS_HZ = 200
ATTITUDE_HZ = 25.0  # its default rate (rig_emulator/link/telemetry/stream_table.py)
#: Simulated seconds per wall second that count as "control rate held" at speed-up 1.
HELD_TARGET = Target(">=", 0.99, "control rate held at speed-up 1")


def _connect(url: str):
    from rig_emulator.testing.rig import connect, recv

    conn = connect(url)
    if recv(conn, ["HEARTBEAT", "ATTITUDE"], timeout=30.0) is None:
        raise RuntimeError(f"no message from the rig at {url} within 30 s")
    return conn


def _window_figures(stream: dict, timing: dict, t_from: float, t_to: float, prefix: str) -> dict:
    from rig_emulator.link.loop_timing import summarize

    s = summarize(timing, t_from, t_to)
    return {
        f"{prefix}_rig_sent_per_wall_s": s["sent_per_wall"],
        f"{prefix}_msgs_per_wall_s": stream["total"] / stream["wall_s"],
        f"{prefix}_msgs_per_sim_s": stream["total"] / stream["sim_span_s"] if stream["sim_span_s"] > 0 else 0.0,
        f"{prefix}_attitude_hz_sim": stream["counts"].get("ATTITUDE", 0) / stream["sim_span_s"]
        if stream["sim_span_s"] > 0 else 0.0,
        f"{prefix}_sim_per_wall": s["sim_per_wall"],
        f"{prefix}_chunk_lateness_p99_ms": s["lateness_p99_ms"],
        f"{prefix}_chunk_busy_p99_ms": s["busy_p99_ms"],
    }


def _requests(conn, figs: dict, prefix: str, commands: int, items) -> None:
    rtt = command_round_trips(conn, commands)
    figs.update(percentiles_ms(rtt, f"{prefix}_command_rtt"))
    mission = mission_round_trip(conn, items)
    for k, v in mission.items():
        figs[f"{prefix}_mission_{k}"] = v


@probe(RIG_PROBE, params={"telemetry_s": 10.0, "stress_s": 5.0, "commands": 300, "mission_items": 1000, "max_s": 5.0},
       quick={"telemetry_s": 1.5, "stress_s": 1.0, "commands": 30, "mission_items": 100, "max_s": 1.0},
       description="rig-emulator serve --speedup 1 + a pymavlink client on loopback", cache=CACHE_GROUP)
def link_rig_probe(telemetry_s: float, stress_s: float, commands: int, mission_items: int, max_s: float = 5.0,
                   warm_up: bool = True) -> dict:
    """Telemetry, command round trips and mission transfer of the served rig at speed-up 1."""
    figs: dict = {"warmup_s": ensure_compiled() if warm_up else 0.0}
    items = mission_items_for(mission_items)
    load = procfs.MachineLoad().start()
    with ServedRig(speedup=1.0) as rig:
        figs["rig_start_s"] = rig.start_s
        conn = _connect(rig.tcp_url)
        cpu0, t0 = procfs.cpu_seconds(rig.pid), time.monotonic()
        default = count_stream(conn, telemetry_s)
        cpu1, t1 = procfs.cpu_seconds(rig.pid), time.monotonic()
        figs["default_rig_cpu_fraction"] = (cpu1 - cpu0) / (t1 - t0)
        _requests(conn, figs, "streams", commands, items)

        conn.mav.request_data_stream_send(1, 1, M.MAV_DATA_STREAM_ALL, STRESS_HZ, 1)
        count_stream(conn, 0.3)  # let the new rates take hold
        cpu2, t2 = procfs.cpu_seconds(rig.pid), time.monotonic()
        stress = count_stream(conn, stress_s)
        cpu3, t3 = procfs.cpu_seconds(rig.pid), time.monotonic()
        figs["stress_rig_cpu_fraction"] = (cpu3 - cpu2) / (t3 - t2)

        conn.mav.request_data_stream_send(1, 1, M.MAV_DATA_STREAM_ALL, 0, 0)
        drain(conn)  # what was in flight (at most 3 s), so that no backlog delays the round trips
        _requests(conn, figs, "quiet", commands, items)
        conn.close()
        rig.stop()
        timing = rig.timing()
    with ServedRig(speedup="max") as fast:
        conn = _connect(fast.tcp_url)
        tm0 = time.monotonic()
        fast_stream = count_stream(conn, max_s)
        tm1 = time.monotonic()
        conn.close()
        fast.stop()
        fast_timing = fast.timing()
    load.stop()
    from rig_emulator.link.loop_timing import summarize

    fast_summary = summarize(fast_timing, tm0, tm1)
    figs["max_speed_rtf"] = fast_summary["sim_per_wall"]
    figs["max_speed_client_msgs_per_wall_s"] = fast_stream["total"] / fast_stream["wall_s"]
    figs.update(_window_figures(default, timing, t0, t1, "default"))
    figs.update(_window_figures(stress, timing, t2, t3, "stress"))
    figs["reanchors"] = timing["reanchors"]
    figs["mission_items"] = len(items)
    figs["commands"] = commands
    figs.update(load.figures())
    return figs


def mission_items_for(n: int):
    if n < 1:
        raise ValueError(f"mission_items must be >= 1, got {n}")
    return make_mission_items(n)


@probe(REFERENCE_PROBE, params={"commands": 300, "mission_items": 1000},
       quick={"commands": 30, "mission_items": 100},
       description="minimal pymavlink responder (no simulation, no streams), same client code")
def link_reference_probe(commands: int, mission_items: int) -> dict:
    """Command round trips and mission transfer against the reference responder."""
    from rig_emulator.testing.rig import connect

    items = mission_items_for(mission_items)
    figs: dict = {}
    load = procfs.MachineLoad().start()
    with ServedProcess("benchmarks.mavlink_responder", RESPONDER_PREFIX) as responder:
        conn = connect(responder.url)
        _requests(conn, figs, "quiet", commands, items)
        figs["responder_cpu_s"] = procfs.cpu_seconds(responder.pid)
        conn.close()
    load.stop()
    figs.update(load.figures())
    return figs


def _ms(stats: ProbeStats, key: str, name: str, note: str = "") -> Metric:
    return stats.metric(key, name, "ms", note=note)


@benchmark("mavlink-link", probes=(RIG_PROBE, REFERENCE_PROBE),
           description="MAVLink at speed-up 1 on loopback: telemetry rate with the control rate held, "
                       "command round trip, 1000-item mission transfer; vs a minimal pymavlink responder")
def mavlink_link(stats: dict[str, ProbeStats]) -> list[Metric]:
    rig, ref = stats[RIG_PROBE], stats[REFERENCE_PROBE]
    out = [
        rig.metric("default_msgs_per_wall_s", "telemetry, default rates: messages per wall s", "msg/s",
                   note="all messages the client received (HEARTBEAT included) at speed-up 1"),
        rig.metric("default_attitude_hz_sim", "telemetry, default rates: ATTITUDE per simulated s", "Hz",
                   note=f"configured {ATTITUDE_HZ:g} Hz"),
        rig.metric("default_sim_per_wall", "telemetry, default rates: simulated s per wall s", "x",
                   targets=(HELD_TARGET,), note="from the rig's chunk record over the client's window"),
        rig.metric("default_rig_cpu_fraction", "telemetry, default rates: rig CPU use", "cores"),
        rig.metric("default_rig_sent_per_wall_s", "telemetry, default rates: messages the rig sent per wall s",
                   "msg/s", note="the rig's own count of messages handed to its sockets, over the client's window"),
        rig.metric("stress_rig_sent_per_wall_s", "telemetry, every stream at 200 Hz: messages the rig sent per wall s",
                   "msg/s", note="REQUEST_DATA_STREAM(ALL, 200 Hz): at most one of each stream per 5 ms chunk; "
                                 "the rig's own count. A loop behind schedule runs the due chunks in one tick, each "
                                 "building its own telemetry (rates hold in simulated time)"),
        rig.metric("stress_msgs_per_wall_s", "telemetry, every stream at 200 Hz: messages the client decoded per wall s",
                   "msg/s", note="below the rig's figure when the pymavlink client cannot decode as fast "
                                 "(the rig then drops what its socket queue cannot hold)"),
        rig.metric("stress_sim_per_wall", "telemetry, every stream at 200 Hz: simulated s per wall s", "x",
                   targets=(HELD_TARGET,)),
        rig.metric("stress_rig_cpu_fraction", "telemetry, every stream at 200 Hz: rig CPU use", "cores"),
        rig.metric("reanchors", "pacing re-anchors (fell > 0.25 s behind)", "count"),
        rig.metric("max_speed_rtf", "--speedup max with a client attached: real-time factor", "x real time",
                   note="simulated s per wall s of a served rig running as fast as it can, default streams"),
    ]
    for cond, label in (("streams", "default streams on"), ("quiet", "streams off")):
        out += [
            _ms(rig, f"{cond}_command_rtt_p50_ms", f"COMMAND_LONG -> ACK p50, {label}"),
            _ms(rig, f"{cond}_command_rtt_p99_ms", f"COMMAND_LONG -> ACK p99, {label}"),
            _ms(rig, f"{cond}_command_rtt_max_ms", f"COMMAND_LONG -> ACK max, {label}"),
            rig.metric(f"{cond}_mission_upload_items_per_s", f"mission upload, {label}", "items/s"),
            rig.metric(f"{cond}_mission_download_items_per_s", f"mission download, {label}", "items/s"),
        ]
    out += [
        _ms(ref, "quiet_command_rtt_p50_ms", "reference: COMMAND_LONG -> ACK p50"),
        _ms(ref, "quiet_command_rtt_p99_ms", "reference: COMMAND_LONG -> ACK p99"),
        ref.metric("quiet_mission_upload_items_per_s", "reference: mission upload", "items/s"),
        ref.metric("quiet_mission_download_items_per_s", "reference: mission download", "items/s"),
    ]
    for cond, label in (("streams", "streams on"), ("quiet", "streams off")):
        out += [
            paired_ratio_metric(rig, f"{cond}_command_rtt_p50_ms", ref, "quiet_command_rtt_p50_ms",
                                f"command round trip p50 vs reference, {label}",
                                note="rig / responder: 1 = as fast as a vehicle that only answers"),
            paired_ratio_metric(rig, f"{cond}_command_rtt_p99_ms", ref, "quiet_command_rtt_p99_ms",
                                f"command round trip p99 vs reference, {label}"),
            paired_ratio_metric(rig, f"{cond}_mission_upload_items_per_s", ref, "quiet_mission_upload_items_per_s",
                                f"mission upload rate vs reference, {label}"),
            paired_ratio_metric(rig, f"{cond}_mission_download_items_per_s", ref,
                                "quiet_mission_download_items_per_s", f"mission download rate vs reference, {label}"),
        ]
    retries = sum(sum(rig.values(f"{c}_mission_retries_{d}")) for c in ("streams", "quiet")
                  for d in ("upload", "download"))
    out.append(Metric("mission client retries (all runs)", retries, "count",
                      note="resends after 0.25 s without an answer; 0 means no request was lost or slow"))
    out.append(rig.metric("machine_busy_cores", "machine load during the rig probe (all processes)", "cores"))
    return out
