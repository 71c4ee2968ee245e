"""served-max: a served rig running as fast as it can with one ground station.

Probe ``served-max-rig`` starts ``rig-emulator serve --speedup max`` (fresh process, numba
cache warm, chunk timing log on, the link tests' plant ``hilms-ideal``) with one ground
station attached at the default stream rates, for ``duration_s`` wall seconds per transport:

* **UDP** (the rig's ``udpin`` endpoint): a plain socket that sends a GCS HEARTBEAT once a
  second and reads every datagram, each parsed whole with pymavlink's parser (the rig packs
  the frames of one tick into as few datagrams as fit in 1400 bytes,
  :mod:`rig_emulator.link.endpoints.sockets`): frames per datagram, bad frames (must be 0);
* **TCP** (``tcpin``), a pymavlink ``mavutil`` client reading everything.

The figure is the **real-time factor**: simulated seconds per wall second from the rig's
chunk record over the client's window (target: >= 100x; 33.7x before the frames
were packed and the link serviced per tick).

Reference (``served-max-core``): the same plant in a fresh process, a ``LiveRig`` stepped in
the serve loop's chunks (20 ms of simulated time at ``--speedup max``) with nothing else -
no link, no snapshot, no telemetry: what the machine gives the rig core right now. The
benchmark prints the served figure, the core's and their ratio per repetition (the share of
the core's speed the served rig keeps with its link), so that a busy machine, which slows
both, does not hide a regression.
"""

from __future__ import annotations

import socket
import time

from protocol.dialect import mavlink as M

from . import procfs
from .harness import Metric, ProbeStats, Target, benchmark, paired_ratio_metric, probe
from .served_rig import ServedRig, ensure_compiled

RIG_PROBE = "served-max-rig"
CORE_PROBE = "served-max-core"
CACHE_GROUP = "served-rig"
AIRFRAME = "hilms-ideal"  # what ServedRig serves (rig_emulator.testing.rig.TEST_AIRFRAME)
TARGET = Target(">=", 100.0, "a served rig as fast as it can run")


def _udp_client(url: str, duration_s: float) -> dict:
    """Read a rig's udpin endpoint for ``duration_s`` wall seconds; returns client-side figures."""
    from protocol.dialect import use_hilms_dialect

    use_hilms_dialect()
    kind, host, port = url.split(":")
    addr = (host, int(port))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(0.2)
    tx = M.MAVLink(None, srcSystem=255, srcComponent=190)
    rx = M.MAVLink(None, srcSystem=255, srcComponent=190)
    rx.robust_parsing = True
    hb = M.MAVLink_heartbeat_message(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, M.MAV_STATE_ACTIVE, 3)
    datagrams = frames = bad = 0
    largest = 0
    first = last = None  # (wall, ATTITUDE time_boot_ms)
    next_hb = 0.0
    t_end = None
    t0 = time.monotonic()
    while True:
        now = time.monotonic()
        if now >= next_hb:
            sock.sendto(hb.pack(tx), addr)
            next_hb = now + 1.0
        if t_end is not None and now >= t_end:
            break
        if t_end is None and now - t0 > 30.0:
            raise RuntimeError("the rig sent nothing over UDP within 30 s")
        try:
            data, _ = sock.recvfrom(65536)
        except socket.timeout:
            continue
        if t_end is None:  # the window starts with the first datagram
            t_end = time.monotonic() + duration_s
            t_start = time.monotonic()
        datagrams += 1
        largest = max(largest, len(data))
        for msg in rx.parse_buffer(data) or []:
            if msg.get_type() == "BAD_DATA":
                bad += 1
                continue
            frames += 1
            if msg.get_type() == "ATTITUDE":
                last = (time.monotonic(), msg.time_boot_ms)
                if first is None:
                    first = last
        if rx.buf_len():  # a frame split across datagrams: the rig never does that
            bad += 1
            rx = M.MAVLink(None, srcSystem=255, srcComponent=190)
            rx.robust_parsing = True
    sock.close()
    wall = time.monotonic() - t_start
    out = {"udp_datagrams_per_wall_s": datagrams / wall, "udp_frames_per_wall_s": frames / wall,
           "udp_frames_per_datagram": frames / max(datagrams, 1), "udp_largest_datagram_bytes": largest,
           "udp_bad_frames": bad, "window": (t_start, t_start + wall)}
    if first is not None and last[0] > first[0]:
        out["udp_client_rtf"] = (last[1] - first[1]) / 1e3 / (last[0] - first[0])
    return out


def _tcp_client(url: str, duration_s: float) -> dict:
    from .link_client import count_stream
    from .mavlink_link import _connect

    conn = _connect(url)
    t0 = time.monotonic()
    stream = count_stream(conn, duration_s)
    t1 = time.monotonic()
    conn.close()
    return {"tcp_frames_per_wall_s": stream["total"] / stream["wall_s"], "window": (t0, t1)}


@probe(RIG_PROBE, params={"duration_s": 5.0}, quick={"duration_s": 1.0}, cache=CACHE_GROUP,
       description="rig-emulator serve --speedup max with one ground station (UDP, then TCP) at default rates")
def served_max_probe(duration_s: float, warm_up: bool = True) -> dict:
    """Real-time factor of the served rig at --speedup max, one client per transport; see the module docstring."""
    from rig_emulator.link.loop_timing import summarize

    figs: dict = {"warmup_s": ensure_compiled() if warm_up else 0.0}
    load = procfs.MachineLoad().start()
    with ServedRig(speedup="max", extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        udp_url = next(u for u in rig.urls if u.startswith("udpin:"))
        cpu0 = procfs.cpu_seconds(rig.pid)
        udp = _udp_client(udp_url, duration_s)
        t_from, t_to = udp.pop("window")
        figs["udp_rig_cpu_fraction"] = (procfs.cpu_seconds(rig.pid) - cpu0) / (t_to - t_from)
        rig.stop()
        udp_summary = summarize(rig.timing(), t_from, t_to)
    figs.update(udp)
    figs["udp_rtf"] = udp_summary["sim_per_wall"]
    figs["udp_rig_sent_per_wall_s"] = udp_summary["sent_per_wall"]
    with ServedRig(speedup="max") as rig:
        tcp = _tcp_client(rig.tcp_url, duration_s)
        t_from, t_to = tcp.pop("window")
        rig.stop()
        tcp_summary = summarize(rig.timing(), t_from, t_to)
    figs.update(tcp)
    figs["tcp_rtf"] = tcp_summary["sim_per_wall"]
    load.stop()
    figs.update(load.figures())
    return figs


@probe(CORE_PROBE, params={"duration_s": 5.0}, quick={"duration_s": 1.0}, cache=CACHE_GROUP,
       description="the served rig's plant stepped in the serve loop's chunks, no link (reference)")
def served_max_core_probe(duration_s: float) -> dict:
    """LiveRig.step in 20 ms chunks for ``duration_s`` wall seconds: simulated s per wall s."""
    from rig_emulator.config.loader import load_config
    from rig_emulator.link.serve import chunk_seconds, prepare_rig

    rig = prepare_rig(load_config(airframe=AIRFRAME))
    chunk_steps = max(1, int(round(chunk_seconds(5.0, 0.0) / rig.dt)))
    rig.step(chunk_steps)  # first call out of the window
    load = procfs.MachineLoad().start()
    sim0, t0 = rig.time_s, time.monotonic()
    t_end = t0 + duration_s
    while time.monotonic() < t_end:
        rig.step(chunk_steps)
    t1 = time.monotonic()
    load.stop()
    return {"core_rtf": (rig.time_s - sim0) / (t1 - t0), **load.figures()}


@benchmark("served-max", probes=(RIG_PROBE, CORE_PROBE),
           description="serve --speedup max with one ground station (UDP and TCP): real-time factor, "
                       "vs the rig core stepped in the same chunks without a link")
def served_max(stats: dict[str, ProbeStats]) -> list[Metric]:
    rig, core = stats[RIG_PROBE], stats[CORE_PROBE]
    return [
        rig.metric("udp_rtf", "served --speedup max, one UDP client: real-time factor", "x real time",
                   targets=(TARGET,), note="simulated s per wall s, the rig's chunk record over the client's window"),
        rig.metric("tcp_rtf", "served --speedup max, one TCP client: real-time factor", "x real time",
                   targets=(TARGET,)),
        core.metric("core_rtf", "reference: the rig core in the same chunks, no link", "x real time"),
        paired_ratio_metric(rig, "udp_rtf", core, "core_rtf", "UDP served / core",
                            note="share of the core's speed the served rig keeps (1 = the link costs nothing)"),
        paired_ratio_metric(rig, "tcp_rtf", core, "core_rtf", "TCP served / core"),
        rig.metric("udp_frames_per_datagram", "UDP: MAVLink frames per datagram", "frames",
                   note="was 1 before packing"),
        rig.metric("udp_datagrams_per_wall_s", "UDP: datagrams per wall s", "1/s"),
        rig.metric("udp_frames_per_wall_s", "UDP: frames the client parsed per wall s", "1/s"),
        rig.metric("udp_largest_datagram_bytes", "UDP: largest datagram", "bytes",
                   targets=(Target("<=", 1400, "under the 1472-byte payload of an Ethernet MTU"),)),
        rig.metric("udp_bad_frames", "UDP: frames the client could not parse", "count",
                   targets=(Target("<=", 0, "every packed frame parses"),)),
        rig.metric("udp_rig_cpu_fraction", "UDP: rig CPU use", "cores"),
    ]
