"""Quick tests of the benchmark harness' logic (never of timings)."""

from __future__ import annotations

import dataclasses
import json
import math
import os

import pytest

from benchmarks import _worker
from benchmarks.harness import (
    BenchmarkError,
    Metric,
    ProbeStats,
    Registry,
    Target,
    format_table,
    format_value,
    median,
    paired_ratio_metric,
    ratio,
    render_report,
    run_suite,
    varying_labels,
    write_json,
)
from benchmarks.rig_core import SCENARIOS, _probe_name, rig_core, rig_simulate_probe
from benchmarks.rotorpy_reference import ROTORPY_BARE


# -- probes used by the end-to-end test (module level: the worker imports them) ---------


def echo_probe(value: float) -> dict:
    return {"value": value, "pid": os.getpid(), "cache": os.environ.get("HILMS_NUMBA_CACHE", "")}


def failing_probe() -> dict:
    raise RuntimeError("deliberate failure")


# -- pure helpers ------------------------------------------------------------------------


def test_median_odd_even_and_errors():
    assert median([3, 1, 2]) == 2
    assert median([4, 1, 3, 2]) == 2.5
    with pytest.raises(BenchmarkError):
        median([])
    with pytest.raises(BenchmarkError):
        median([1.0, float("nan")])


def test_ratio():
    assert ratio(300.0, 0.5) == 600.0
    with pytest.raises(BenchmarkError, match="non-positive"):
        ratio(1.0, 0.0)
    with pytest.raises(BenchmarkError, match="non-finite"):
        ratio(float("inf"), 1.0)


def test_format_value():
    assert format_value(None) == "-"
    assert format_value(0.6412) == "0.641"
    assert format_value(3.14159) == "3.14"
    assert format_value(35.25) == "35.2"
    assert format_value(1234.6) == "1,235"


def test_format_table_aligns_and_checks_width():
    t = format_table(("a", "bb"), [["xxx", "1"], ["y", "22"]])
    lines = t.splitlines()
    assert lines[0] == "a    bb"
    assert lines[1] == "---  --"
    assert lines[2] == "xxx  1"
    assert lines[3] == "y    22"
    with pytest.raises(ValueError):
        format_table(("a",), [["1", "2"]])


def test_target():
    t = Target(">=", 200, "sweeps of many rigs")
    assert t.met(200) and not t.met(199.9)
    assert Target("<=", 5, "x").met(4)
    assert t.describe() == ">= 200 (sweeps of many rigs)"
    with pytest.raises(ValueError):
        Target(">", 1, "x")


# -- registry ------------------------------------------------------------------------------


def test_registry_registration_and_selection():
    r = Registry()
    r.add_probe("a", echo_probe, {"value": 1.0}, quick={"value": 2.0})
    r.add_probe("b", echo_probe, {"value": 3.0})
    assert r.probes["a"].params_for(True) == {"value": 2.0}
    assert r.probes["b"].params_for(True) == {"value": 3.0}
    with pytest.raises(BenchmarkError, match="twice"):
        r.add_probe("a", echo_probe)
    with pytest.raises(BenchmarkError, match="unregistered"):
        r.add_benchmark("x", ["nope"], lambda s: [])

    @r.benchmark("first", probes=("b", "a"))
    def first(stats):
        """First benchmark."""
        return []

    r.add_benchmark("second", ["a"], lambda s: [])
    assert r.benchmarks["first"].description == "First benchmark."
    assert [b.name for b in r.select(None)] == ["first", "second"]
    assert [b.name for b in r.select(["second"])] == ["second"]
    assert [p.name for p in r.probes_for(r.select(None))] == ["b", "a"]
    with pytest.raises(BenchmarkError, match="available"):
        r.select(["missing"])


def test_probe_must_be_importable_and_params_json():
    r = Registry()
    with pytest.raises(BenchmarkError, match="module level"):
        r.add_probe("lam", lambda: {})
    with pytest.raises(BenchmarkError, match="JSON"):
        r.add_probe("obj", echo_probe, {"value": object()})


# -- statistics ------------------------------------------------------------------------------


def test_probe_stats_metric_first_and_pairing():
    s = ProbeStats("rig", [{"rtf": 100.0, "t": 5.0}, {"rtf": 300.0, "t": 1.0}, {"rtf": 200.0, "t": 2.0}])
    ref = ProbeStats("ref", [{"rtf": 0.5}, {"rtf": 0.5}, {"rtf": 0.25}])
    m = s.metric("rtf", "speed", "x", targets=(Target(">=", 200, "i2"),))
    assert (m.value, m.low, m.high) == (200.0, 100.0, 300.0)
    assert s.first("t") == 5.0
    assert s.median("t", skip_first=True) == 1.5
    r = paired_ratio_metric(s, "rtf", ref, "rtf", "vs ref")
    assert r.reference == "ref"
    assert (r.low, r.value, r.high) == (200.0, 600.0, 800.0)
    with pytest.raises(BenchmarkError, match="did not report"):
        s.values("missing")
    with pytest.raises(BenchmarkError, match="cannot pair"):
        paired_ratio_metric(s, "rtf", ProbeStats("e", [{"rtf": 1.0}]), "rtf", "x")


def test_varying_labels():
    assert varying_labels([{"v": "a", "x": 1.0}, {"v": "a", "x": 2.0}]) == {}
    assert varying_labels([{"v": "a"}, {"v": "b"}, {"v": "a"}]) == {"v": ["a", "b"]}
    doc_runs = [{"source": "numba-1", "rtf": 1.0}, {"source": "numba-2", "rtf": 1.0}]
    assert "source" in varying_labels(doc_runs)


def test_worker_rejects_bad_figures():
    assert _worker._check_figures({"a": 1, "b": "s", "c": None}) == {"a": 1, "b": "s", "c": None}
    with pytest.raises(ValueError):
        _worker._check_figures({"a": float("nan")})
    with pytest.raises(TypeError):
        _worker._check_figures({"a": [1, 2]})
    with pytest.raises(TypeError):
        _worker._check_figures([1])


# -- rig-core with a stand-in for rig_emulator.api.simulate ----------------------------------


@dataclasses.dataclass
class FakeResult:
    sim_time_s: float
    wall_time_s: float
    steps: int
    mean_errors: dict


class FakeSimulate:
    """Stand-in for the rig API: 1 kHz steps, a 'compile' on the first call only."""

    def __init__(self, wall_per_sim_s: float = 1 / 400, wall_time_s=None):
        self.calls = []
        self.wall_per_sim_s = wall_per_sim_s
        self.wall_time_s = wall_time_s

    def __call__(self, scenario, strategy="smc-flc", duration=10.0, seed=0, **overrides):
        self.calls.append((scenario, strategy, duration, seed, overrides))
        wall = self.wall_time_s if self.wall_time_s is not None else duration * self.wall_per_sim_s
        return FakeResult(duration, wall, int(round(duration * 1000)), {"position_m": 0.01, "label": "x"})


def test_rig_probe_with_stand_in():
    fake = FakeSimulate()
    figs = rig_simulate_probe("helix", "smc-flc", 30.0, 7, inner=3, _simulate=fake)
    assert len(fake.calls) == 4
    assert all(c == ("helix", "smc-flc", 30.0, 7, {}) for c in fake.calls)
    assert math.isclose(figs["rtf"], 400.0)
    assert figs["steps"] == 30000 and math.isclose(figs["physics_hz"], 1000.0)
    assert math.isclose(figs["us_per_step"], 2.5)
    assert figs["mean_error.position_m"] == 0.01
    assert "mean_error.label" not in figs
    assert figs["first_call_s"] >= 0 and figs["rtf_end_to_end"] > 0
    assert figs["source"] == "stand-in"
    json.dumps(figs)


def test_rig_probe_rejects_bad_results():
    with pytest.raises(ValueError, match="wall_time_s"):
        rig_simulate_probe("hover", "smc-flc", 1.0, 0, 1, _simulate=FakeSimulate(wall_time_s=0.0))

    def short(scenario, **kw):
        return FakeResult(0.5, 0.01, 500, {})

    with pytest.raises(ValueError, match="requested"):
        rig_simulate_probe("hover", "smc-flc", 1.0, 0, 1, _simulate=short)


def test_rig_core_summary_targets():
    rig_run = {"rtf": 600.0, "rtf_end_to_end": 400.0, "us_per_step": 1.7, "physics_hz": 1000.0,
               "first_call_s": 6.0, "mean_error.position_m": 0.01}
    stats = {ROTORPY_BARE: ProbeStats(ROTORPY_BARE, [{"rtf": 0.5}, {"rtf": 0.5}])}
    core_run = {**rig_run, "rtf": 1200.0}
    ideal_run = {**rig_run, "rtf": 750.0}
    for sc in SCENARIOS:
        stats[_probe_name(sc, "full")] = ProbeStats(_probe_name(sc, "full"), [dict(rig_run), {**rig_run, "first_call_s": 0.7}])
        stats[_probe_name(sc, "core")] = ProbeStats(_probe_name(sc, "core"), [dict(core_run), dict(core_run)])
        stats[_probe_name(sc, "ideal")] = ProbeStats(_probe_name(sc, "ideal"), [dict(ideal_run), dict(ideal_run)])
    metrics = {m.name: m for m in rig_core(stats)}
    rtf = metrics["hover: full-fidelity real-time factor"]
    # the 300x and the 500x for the hardware rig
    assert rtf.value == 600.0 and len(rtf.targets) == 2 and all(t.met(rtf.value) for t in rtf.targets)
    assert not all(t.met(450.0) for t in rtf.targets)
    vs = metrics["helix: full-fidelity speed vs RotorPy"]
    assert vs.value == 1200.0 and vs.reference == ROTORPY_BARE and vs.targets[0].met(vs.value)
    cost = metrics["hover: sensing cost (core / full)"]
    assert cost.value == 2.0 and cost.targets[0].met(cost.value)
    assert metrics["helix: core real-time factor (no sensor models)"].value == 1200.0
    assert metrics["hover: ideal plant (hilms-ideal) full-fidelity real-time factor"].value == 750.0
    assert metrics["helix: hardware rig speed vs the ideal plant"].value == pytest.approx(0.8)
    assert metrics["hover: first call, cold numba cache"].value == 6.0
    assert metrics["hover: first call, warm numba cache"].value == 0.7



def test_hardware_rig_summary_pairs_the_two_plants():
    from benchmarks.hardware_rig import HILMS, IDEAL, hardware_rig

    run = {"rtf": 520.0, "us_per_step": 1.9, "first_call_s": 80.0}
    stats = {HILMS: ProbeStats(HILMS, [dict(run), {**run, "rtf": 400.0, "first_call_s": 0.8}]),
             IDEAL: ProbeStats(IDEAL, [{**run, "rtf": 650.0, "first_call_s": 79.0}, {**run, "rtf": 500.0}])}
    metrics = {m.name: m for m in hardware_rig(stats)}
    rtf = metrics["hilms: real-time factor"]
    assert rtf.value == 460.0 and not rtf.targets[0].met(rtf.value) and rtf.targets[0].met(520.0)
    ratio = metrics["hilms speed / hilms-ideal speed"]
    assert ratio.value == pytest.approx(0.8) and ratio.reference == IDEAL  # 520/650 and 400/500, paired
    assert metrics["hilms: first call, cold numba cache"].value == 80.0
    assert metrics["hilms-ideal: first call, cold numba cache"].value == 79.0
    assert metrics["hilms: first call, warm numba cache"].value == 0.8

# -- end to end: fresh subprocesses, interleaving, failures, report, JSON ---------------------


def test_run_suite_end_to_end(tmp_path):
    r = Registry()
    r.add_probe("subject", echo_probe, {"value": 300.0}, quick={"value": 400.0})
    r.add_probe("reference", echo_probe, {"value": 0.5})
    r.add_probe("broken", failing_probe)

    @r.benchmark("speed", probes=("subject", "reference"))
    def speed(stats):
        return [paired_ratio_metric(stats["subject"], "value", stats["reference"], "value", "ratio",
                                    targets=(Target(">=", 400, "goal"),))]

    r.add_benchmark("bad", ["broken"], lambda s: [])
    doc = run_suite(r, repeat=2, quick=True, log=open(os.devnull, "w"))

    runs = doc["probes"]["subject"]["runs"]
    assert len(runs) == 2 and runs[0]["pid"] != runs[1]["pid"]  # fresh process per repetition
    assert runs[0]["cache"] and runs[0]["cache"] == runs[1]["cache"]  # one numba cache per probe
    assert doc["probes"]["reference"]["runs"][0]["cache"] != runs[0]["cache"]
    assert not os.path.exists(runs[0]["cache"])  # removed afterwards
    speed_entry = doc["benchmarks"]["speed"]
    assert speed_entry["status"] == "ok"
    (m,) = speed_entry["metrics"]
    assert m["value"] == 800.0 and m["reference"] == "reference" and m["targets"][0]["met"]
    bad = doc["benchmarks"]["bad"]
    assert bad["status"] == "error" and "deliberate failure" in bad["error"]
    assert len(doc["probes"]["broken"]["runs"]) == 0  # not retried after failing

    text = render_report(doc)
    assert "speed" in text and "800" in text and "ERRORS" in text and "deliberate failure" in text
    out = write_json(doc, tmp_path / "sub" / "r.json")
    assert json.loads(out.read_text())["benchmarks"]["speed"]["metrics"][0]["value"] == 800.0


def test_cache_groups_share_a_numba_cache_and_summary_bugs_are_reported():
    r = Registry()
    r.add_probe("a", echo_probe, {"value": 1.0}, cache="g")
    r.add_probe("b", echo_probe, {"value": 2.0}, cache="g")
    r.add_probe("c", echo_probe, {"value": 3.0})
    r.add_benchmark("ok", ["a", "b", "c"], lambda s: [Metric("m", 1.0, "x")])
    r.add_benchmark("buggy", ["a"], lambda s: [1 / 0])
    doc = run_suite(r, repeat=1, log=open(os.devnull, "w"))
    cache = {n: doc["probes"][n]["runs"][0]["cache"] for n in "abc"}
    assert cache["a"] == cache["b"] != cache["c"]
    assert doc["probes"]["a"]["numba_cache"] == "shared by group 'g'" and doc["probes"]["c"]["numba_cache"] == "own"
    assert doc["benchmarks"]["ok"]["status"] == "ok"
    assert doc["benchmarks"]["buggy"]["status"] == "error" and "ZeroDivisionError" in doc["benchmarks"]["buggy"]["error"]


def test_paired_difference_metric():
    from benchmarks.harness import paired_difference_metric

    a = ProbeStats("a", [{"x": 3.0}, {"x": 5.0}, {"x": 4.0}])
    b = ProbeStats("b", [{"x": 1.0}, {"x": 1.0}, {"x": 3.0}])
    m = paired_difference_metric(a, "x", b, "x", "excess", "ms")
    assert (m.value, m.low, m.high, m.reference) == (2.0, 1.0, 4.0, "b")
    with pytest.raises(BenchmarkError, match="cannot pair"):
        paired_difference_metric(a, "x", ProbeStats("e", [{"x": 1.0}]), "x", "d", "ms")


def test_run_suite_rejects_bad_settings():
    r = Registry()
    r.add_probe("p", echo_probe, {"value": 1.0})
    r.add_benchmark("b", ["p"], lambda s: [Metric("m", 1.0, "x")])
    with pytest.raises(BenchmarkError):
        run_suite(r, repeat=0)
    with pytest.raises(BenchmarkError, match="unknown"):
        run_suite(r, only=["zzz"])
