"""Smoke runs of the mavlink-link, jitter and memory benchmarks: every probe once with tiny
parameters (real rig processes, real sockets), then each summary on what the probes
returned. Shapes and sanity only, never timings. The rig probes skip their warm-up rig
(``warm_up=False``): the suite's numba cache is warm (scripts/test.sh compiles first)."""

from __future__ import annotations

import math

import pytest

from benchmarks import jitter, mavlink_link, memory
from benchmarks.harness import REGISTRY, Metric, ProbeStats
from benchmarks.link_client import mission_items, percentiles_ms


def _finite(figs: dict, keys) -> None:
    for k in keys:
        assert k in figs, k
        assert isinstance(figs[k], (int, float)) and math.isfinite(figs[k]), (k, figs[k])


def _summary(func, runs: dict) -> dict[str, Metric]:
    """Run a benchmark summary on two identical repetitions of each probe's figures."""
    metrics = func({name: ProbeStats(name, [dict(r), dict(r)]) for name, r in runs.items()})
    assert metrics and all(isinstance(m, Metric) for m in metrics)
    for m in metrics:
        assert math.isfinite(m.value), m
    return {m.name: m for m in metrics}


def test_new_benchmarks_are_registered_with_a_shared_cache():
    for bench, probes in (("mavlink-link", (mavlink_link.RIG_PROBE, mavlink_link.REFERENCE_PROBE)),
                          ("jitter", (jitter.RIG_PROBE, jitter.PACER_PROBE)),
                          ("memory", (memory.RIG_PROBE, memory.HEADLESS_PROBE, memory.FLOOR_PROBE))):
        assert REGISTRY.benchmarks[bench].probes == probes
    for name in (mavlink_link.RIG_PROBE, jitter.RIG_PROBE, memory.RIG_PROBE, memory.HEADLESS_PROBE):
        assert REGISTRY.probes[name].cache == "served-rig"


def test_mission_items_and_percentiles():
    items = mission_items(7)
    assert [it.seq for it in items] == list(range(7)) and [it.current for it in items] == [1] + [0] * 6
    assert all(round(it.x * 1e4) / 1e4 == it.x for it in items)  # exact in MISSION_ITEM_INT (1e-4 m)
    p = percentiles_ms([0.001] * 99 + [0.003], "x")
    assert p["x_p50_ms"] == pytest.approx(1.0) and p["x_max_ms"] == pytest.approx(3.0)
    with pytest.raises(ValueError):
        percentiles_ms([], "x")


def test_mavlink_link_probes_and_summary():
    ref = mavlink_link.link_reference_probe(commands=5, mission_items=20)
    _finite(ref, ["quiet_command_rtt_p50_ms", "quiet_command_rtt_p99_ms", "quiet_mission_upload_items_per_s",
                  "quiet_mission_download_items_per_s", "machine_busy_cores"])
    rig = mavlink_link.link_rig_probe(telemetry_s=0.5, stress_s=0.3, commands=5, mission_items=20, warm_up=False)
    _finite(rig, ["default_msgs_per_wall_s", "default_rig_sent_per_wall_s", "default_sim_per_wall",
                  "stress_rig_sent_per_wall_s", "streams_command_rtt_p99_ms", "quiet_command_rtt_p50_ms",
                  "streams_mission_upload_items_per_s", "quiet_mission_download_items_per_s", "reanchors"])
    assert rig["default_msgs_per_wall_s"] > 0 and rig["mission_items"] == 20
    assert rig["stress_rig_sent_per_wall_s"] > rig["default_rig_sent_per_wall_s"]  # every stream at 200 Hz
    m = _summary(mavlink_link.mavlink_link, {mavlink_link.RIG_PROBE: rig, mavlink_link.REFERENCE_PROBE: ref})
    ratio = m["command round trip p50 vs reference, streams off"]
    assert ratio.reference == mavlink_link.REFERENCE_PROBE
    assert ratio.value == pytest.approx(rig["quiet_command_rtt_p50_ms"] / ref["quiet_command_rtt_p50_ms"])
    assert m["telemetry, default rates: simulated s per wall s"].targets


def test_jitter_probes_and_summary():
    pacer = jitter.jitter_pacer_probe(duration_s=1.0)
    _finite(pacer, ["period_err_p99_ms", "lateness_p99_ms", "sim_per_wall", "cpu_fraction"])
    assert pacer["chunks"] >= 50 and pacer["nominal_period_ms"] == pytest.approx(5.0)
    rig = jitter.jitter_rig_probe(duration_s=0.5, warm_up=False)
    _finite(rig, ["period_err_p50_ms", "period_err_p99_ms", "lateness_p99_ms", "busy_p99_ms", "sim_per_wall",
                  "rig_cpu_fraction", "client_msgs_per_wall_s", "machine_busy_cores"])
    assert rig["chunks"] >= 20 and rig["client_msgs_per_wall_s"] > 0
    m = _summary(jitter.jitter, {jitter.RIG_PROBE: rig, jitter.PACER_PROBE: pacer})
    excess = m["period error p99 above empty loop"]
    assert excess.value == pytest.approx(rig["period_err_p99_ms"] - pacer["period_err_p99_ms"])
    target = m["chunk period error p99"].targets[0]
    assert (target.op, target.value) == ("<=", 1.0)


def test_memory_probes_and_summary():
    floor = memory.mem_floor_probe()
    _finite(floor, ["python_rss_mib", "numpy_pymavlink_rss_mib", "with_numba_scipy_rss_mib"])
    assert floor["python_rss_mib"] < floor["numpy_pymavlink_rss_mib"] < floor["with_numba_scipy_rss_mib"]
    run = memory.mem_headless_probe(duration=2.0)
    _finite(run, ["rss_before_mib", "run_peak_mib", "series_mib"])
    assert run["sim_time_s"] == pytest.approx(2.0) and run["run_peak_mib"] >= run["rss_before_mib"] * 0.9
    rig = memory.mem_rig_probe(idle_s=0.2, fly_s=0.6, warm_up=False)
    _finite(rig, ["idle_rss_mib", "flying_rss_mib", "lifetime_hwm_mib", "flight_msgs_received"])
    assert rig["lifetime_hwm_mib"] >= rig["flying_rss_mib"] > 0
    m = _summary(memory.memory, {memory.RIG_PROBE: rig, memory.HEADLESS_PROBE: run, memory.FLOOR_PROBE: floor})
    assert m["idle rig RSS vs reference"].value == pytest.approx(rig["idle_rss_mib"] / floor["numpy_pymavlink_rss_mib"])
