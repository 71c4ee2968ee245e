"""px4-lockstep: a flight stack flying the rig in lockstep over PX4's Simulator MAVLink API.

Probe ``px4-lockstep-rig`` starts ``rig-emulator serve --px4-simulator 127.0.0.1:0`` (a
fresh process, the numba cache warmed by a throw-away session first; the ground link on a
TCP port nobody uses) and flies it with the pymavlink stand-in flight stack of
:mod:`gcs_tools.px4_peer` in the probe process (it connects, answers every HIL_SENSOR with
one HIL_ACTUATOR_CONTROLS, takes off to 1 m and holds) for ``sim_s`` simulated seconds at
PX4's 250 Hz step. Figures: the real-time factor (simulated s / wall s over the flight),
wall microseconds per step, the rig's CPU use.

Probe ``px4-lockstep-reference`` runs the same client against
:mod:`benchmarks.px4_echo_simulator`, a simulator that only answers (same messages, no
physics): the floor of this client and loopback TCP. The benchmark reports the rig's
figures and the ratio of its real-time factor to the reference's.

The client is Python (pymavlink decoding and encoding each message): a compiled flight
stack such as PX4 spends far less per step, so the rig's own share is the interesting
part: ``rig_cpu_us_per_step``.
"""

from __future__ import annotations

import time

from . import procfs
from .harness import Target, benchmark, paired_ratio_metric, probe
from .link_client import ServedProcess
from .px4_echo_simulator import PREFIX as ECHO_PREFIX

RIG_PROBE = "px4-lockstep-rig"
REFERENCE_PROBE = "px4-lockstep-reference"
RIG_PREFIX = "rig-emulator: px4 simulator on "
RTF_TARGET = Target(">=", 10.0, "at least 10x real time at a 250 Hz step")


def _fly(url: str, sim_s: float):
    from gcs_tools.px4_peer import StreamLink, fly

    _, host, port = url.split(":")
    link = StreamLink.tcp(host, int(port), timeout_s=60.0)
    try:
        return fly(link, sim_s, record=False)
    finally:
        link.close()


def _rig(args=()):
    return ServedProcess("rig_emulator", RIG_PREFIX, start_timeout_s=600.0,
                         args=["serve", "--px4-simulator", "127.0.0.1:0", "--mavlink", "tcpin:127.0.0.1:0",
                               "--no-persist", *args])


@probe(RIG_PROBE, params={"sim_s": 20.0}, quick={"sim_s": 2.0},
       description="rig-emulator serve --px4-simulator + the pymavlink stand-in flight stack, 250 Hz lockstep",
       cache="served-rig")
def px4_lockstep_rig_probe(sim_s: float, warm_up: bool = True) -> dict:
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
    figs["wall_us_per_step"] = log.wall_s / log.steps * 1e6
    figs["rig_cpu_us_per_step"] = (cpu1 - cpu0) / log.steps * 1e6
    figs["peer_cpu_us_per_step"] = (peer1 - peer0) / log.steps * 1e6  # this process: the stand-in flight stack
    figs["steps"] = log.steps
    figs.update(load.figures())
    return figs


@probe(REFERENCE_PROBE, params={"sim_s": 20.0}, quick={"sim_s": 2.0},
       description="the same client against a simulator that only answers (benchmarks.px4_echo_simulator)")
def px4_lockstep_reference_probe(sim_s: float) -> dict:
    load = procfs.MachineLoad().start()
    with ServedProcess("benchmarks.px4_echo_simulator", ECHO_PREFIX) as echo:
        cpu0, peer0 = procfs.cpu_seconds(echo.pid), time.process_time()
        log = _fly(echo.url, sim_s)
        cpu1, peer1 = procfs.cpu_seconds(echo.pid), time.process_time()
    load.stop()
    figs = {"rtf": log.sim_time_s / log.wall_s, "wall_us_per_step": log.wall_s / log.steps * 1e6,
            "sim_cpu_us_per_step": (cpu1 - cpu0) / log.steps * 1e6,
            "peer_cpu_us_per_step": (peer1 - peer0) / log.steps * 1e6, "steps": log.steps}
    figs.update(load.figures())
    return figs


@benchmark("px4-lockstep", probes=(RIG_PROBE, REFERENCE_PROBE),
           description="PX4 Simulator MAVLink API in lockstep at 250 Hz: real-time factor with a pymavlink "
                       "flight stack; vs a simulator that only answers")
def px4_lockstep(stats) -> list:
    rig, ref = stats[RIG_PROBE], stats[REFERENCE_PROBE]
    return [
        rig.metric("rtf", "lockstep real-time factor, 250 Hz step", "x real time", targets=(RTF_TARGET,),
                   note="simulated s / wall s of the stand-in flight stack's flight (hover at 1 m)"),
        rig.metric("wall_us_per_step", "wall time per lockstep step (both sides + loopback)", "us"),
        rig.metric("rig_cpu_us_per_step", "rig CPU time per step", "us",
                   note="physics (4 x 1 ms), sensors, estimators, HIL messages, ground link"),
        rig.metric("peer_cpu_us_per_step", "stand-in flight stack (pymavlink peer) CPU time per step", "us",
                   note="the other half of every step: the pair takes turns, so rig + peer CPU bounds the rate"),
        ref.metric("rtf", "reference: real-time factor against the answer-only simulator", "x real time"),
        ref.metric("sim_cpu_us_per_step", "reference: simulator CPU time per step", "us"),
        paired_ratio_metric(rig, "rtf", ref, "rtf", "rig / answer-only simulator, real-time factor", "x",
                            note="1.0 would mean the rig costs nothing beyond answering"),
    ]
