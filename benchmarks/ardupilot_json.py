"""ardupilot-json: a flight stack flying the rig in lockstep over ArduPilot's JSON interface.

Probe ``ardupilot-json-rig`` starts ``rig-emulator serve --ardupilot-json 127.0.0.1:0`` (a
fresh process, the numba cache warmed by a throw-away session first; the ground link on a TCP
port nobody uses) and flies it with the stand-in ArduPilot of :mod:`gcs_tools.ardupilot_peer`
in the probe process (a servo packet a frame, SIM_JSON's parser on every answer, take-off to
1 m and hold) for ``sim_s`` simulated seconds at 1 ms a frame. Figures: the real-time factor,
wall microseconds per frame, the rig's CPU per frame and the stand-in's.

Probe ``ardupilot-json-reference`` runs the same client against
:mod:`benchmarks.ardupilot_echo_physics`, a physics that only answers: the floor of this client
and loopback UDP. The benchmark reports the rig's figures and the ratio of its real-time factor
to the reference's. ArduCopter itself, compiled, spends less per frame than the Python stand-in.
"""

from __future__ import annotations

import time

from . import procfs
from .ardupilot_echo_physics import PREFIX as ECHO_PREFIX
from .harness import benchmark, paired_ratio_metric, probe
from .link_client import ServedProcess

RIG_PROBE = "ardupilot-json-rig"
REFERENCE_PROBE = "ardupilot-json-reference"
RIG_PREFIX = "rig-emulator: ardupilot json physics on "


def _fly(url: str, sim_s: float):
    from gcs_tools.ardupilot_peer import JsonLink, fly

    _, host, port = url.split()[0].split(":")
    link = JsonLink(host, int(port), timeout_s=600.0)  # a bound: a cold cache compiles at the first frame
    try:
        return fly(link, sim_s)
    finally:
        link.close()


def _rig(args=()):
    return ServedProcess("rig_emulator", RIG_PREFIX, start_timeout_s=600.0,
                         args=["serve", "--ardupilot-json", "127.0.0.1:0", "--mavlink", "tcpin:127.0.0.1:0",
                               "--no-persist", *args])


@probe(RIG_PROBE, params={"sim_s": 10.0}, quick={"sim_s": 1.0},
       description="rig-emulator serve --ardupilot-json + the stand-in ArduPilot, 1 ms a frame",
       cache="served-rig")
def ardupilot_json_rig_probe(sim_s: float, warm_up: bool = True) -> dict:
    figs: dict = {}
    if warm_up:  # compile (or load) the external-control loop in a throw-away rig
        t0 = time.perf_counter()
        with _rig(["--duration", "0.2"]) as warm:
            _fly(warm.url, 0.1)
        figs["warmup_s"] = time.perf_counter() - t0
    load = procfs.MachineLoad().start()
    rig = _rig()
    try:
        cpu0, peer0 = procfs.cpu_seconds(rig.pid), time.process_time()
        log = _fly(rig.url, sim_s)
        cpu1, peer1 = procfs.cpu_seconds(rig.pid), time.process_time()
    finally:
        rig.stop()
    load.stop()
    figs["rtf"] = log.sim_time_s / log.wall_s
    figs["wall_us_per_frame"] = log.wall_s / log.frames * 1e6
    figs["rig_cpu_us_per_frame"] = (cpu1 - cpu0) / log.frames * 1e6
    figs["peer_cpu_us_per_frame"] = (peer1 - peer0) / log.frames * 1e6
    figs["frames"] = log.frames
    figs.update(load.figures())
    return figs


@probe(REFERENCE_PROBE, params={"sim_s": 10.0}, quick={"sim_s": 1.0},
       description="the same client against a physics that only answers (benchmarks.ardupilot_echo_physics)")
def ardupilot_json_reference_probe(sim_s: float) -> dict:
    load = procfs.MachineLoad().start()
    with ServedProcess("benchmarks.ardupilot_echo_physics", ECHO_PREFIX) as echo:
        cpu0, peer0 = procfs.cpu_seconds(echo.pid), time.process_time()
        log = _fly(echo.url, sim_s)
        cpu1, peer1 = procfs.cpu_seconds(echo.pid), time.process_time()
    load.stop()
    figs = {"rtf": log.sim_time_s / log.wall_s, "wall_us_per_frame": log.wall_s / log.frames * 1e6,
            "sim_cpu_us_per_frame": (cpu1 - cpu0) / log.frames * 1e6,
            "peer_cpu_us_per_frame": (peer1 - peer0) / log.frames * 1e6, "frames": log.frames}
    figs.update(load.figures())
    return figs


@benchmark("ardupilot-json", probes=(RIG_PROBE, REFERENCE_PROBE),
           description="ArduPilot's JSON interface in lockstep at 1 ms a frame: real-time factor with the "
                       "stand-in ArduPilot; vs a physics that only answers")
def ardupilot_json(stats) -> list:
    rig, ref = stats[RIG_PROBE], stats[REFERENCE_PROBE]
    return [
        rig.metric("rtf", "lockstep real-time factor, 1 ms a frame", "x real time",
                   note="simulated s / wall s of the stand-in's flight (hover at 1 m)"),
        rig.metric("wall_us_per_frame", "wall time per frame (both sides + loopback)", "us"),
        rig.metric("rig_cpu_us_per_frame", "rig CPU time per frame", "us",
                   note="physics (1 ms), sensors, estimators, the JSON answer, ground link"),
        rig.metric("peer_cpu_us_per_frame", "stand-in ArduPilot CPU time per frame", "us",
                   note="the other half of every frame: the pair takes turns"),
        ref.metric("rtf", "reference: real-time factor against the answer-only physics", "x real time"),
        ref.metric("sim_cpu_us_per_frame", "reference: physics CPU time per frame", "us"),
        paired_ratio_metric(rig, "rtf", ref, "rtf", "rig / answer-only physics, real-time factor", "x",
                            note="1.0 would mean the rig costs nothing beyond answering"),
    ]
