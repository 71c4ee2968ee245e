"""Smoke run of the many-rigs benchmark: its probes with tiny sweeps (real worker processes,
a local Dask cluster), then its summary on what they returned. Shapes only, never timings."""

from __future__ import annotations

import math

import pytest

from benchmarks import many_rigs
from benchmarks.harness import REGISTRY, ProbeStats


def test_jobs_spread_the_frequency_and_share_one_calibration(tmp_path):
    assert many_rigs.omegas(1) == [0.2]
    w = many_rigs.omegas(5)
    assert w[0] == pytest.approx(0.2) and w[-1] == pytest.approx(2.0) and w == sorted(w)
    jobs = many_rigs.make_jobs(3, 1.0, str(tmp_path / "cal.json"))
    assert len({j.seed for j in jobs}) == 1 and all(j.columns == () for j in jobs)
    assert [dict(j.overrides)["guidance.omega"] for j in jobs] == pytest.approx(many_rigs.omegas(3))
    assert all(dict(j.overrides)["sensors.calibration_file"] == str(tmp_path / "cal.json") for j in jobs)
    assert REGISTRY.benchmarks["many-rigs"].probes == ("sweep-single", "sweep-n10", "sweep-n100", "sweep-n1000")
    assert REGISTRY.probes["sweep-n1000"].params_for(False) == {"n": 1000, "duration": many_rigs.DURATION_S}


def test_probes_and_summary(monkeypatch):
    monkeypatch.setenv(many_rigs.SCHEDULER_ENV, "local")
    for key, value in many_rigs.SINGLE_THREAD_ENV.items():  # the probes set these; restored after the test
        monkeypatch.setenv(key, value)
    single = many_rigs.sweep_single_probe(jobs=2, duration=0.5)
    for k in ("rtf", "rtf_cpu", "serial_rig_s_per_wall_s", "serial_rig_s_per_cpu_s", "setup_cpu_s_per_rig",
              "setup_cpu_s_per_rig_calibrating", "run_cpu_s_per_rig"):
        assert math.isfinite(single[k]) and single[k] > 0, k
    sweep = many_rigs.sweep_probe(n=3, duration=0.5)
    assert sweep["n"] == 3 and sweep["cold_rig_s"] == pytest.approx(1.5) and sweep["dask_rig_s"] == pytest.approx(1.5)
    assert sweep["warm_sweeps"] >= 1 and sweep["rig_s"] == pytest.approx(1.5 * sweep["warm_sweeps"])
    for k in ("rig_s_per_wall_s", "rig_s_per_cpu_s", "cores_used", "dask_rig_s_per_wall_s", "ref_rtf", "ref_rtf_cpu",
              "cold_rig_s_per_wall_s", "pool_start_s", "ref_drift"):
        assert math.isfinite(sweep[k]) and sweep[k] > 0, k
    stats = {many_rigs.SINGLE_PROBE: ProbeStats(many_rigs.SINGLE_PROBE, [single])}
    for n in many_rigs.SIZES:
        stats[many_rigs.probe_name(n)] = ProbeStats(many_rigs.probe_name(n), [sweep])
    metrics = {m.name: m for m in many_rigs.many_rigs(stats)}
    eff = metrics["N=3: parallel efficiency (warm pool)"]
    assert eff.value == pytest.approx(sweep["rig_s_per_wall_s"] / (sweep["ref_rtf"] * sweep["cores"]))
    assert eff.targets[0].value == 0.8 and eff.reference.startswith("sweep-n")
    paired = metrics["N=3: parallel efficiency (warm) vs the sweep-single probe"]
    assert paired.value == pytest.approx(sweep["rig_s_per_wall_s"] / (single["rtf"] * sweep["cores"]))
    cold = metrics["N=3: parallel efficiency (cold, pool start included)"]
    assert cold.value == pytest.approx(sweep["cold_rig_s_per_wall_s"] / (sweep["ref_rtf"] * sweep["cores"]))
    assert cold.value < eff.value  # the pool's start is in the cold sweep's wall time
    assert "N=3 on Dask: parallel efficiency" in metrics
