"""The serve loop's chunk timing record (rig_emulator/link/loop_timing.py, --timing-log)."""

import math
import subprocess
import sys

import numpy as np
import pytest

from rig_emulator.link import loop_timing
from rig_emulator.link.loop_timing import LoopTiming, summarize


def _fill(t: LoopTiming, n: int, period=0.005, late=0.0001):
    for k in range(n):
        due = 10.0 + (k + 1) * period
        t.record(due, due + late, due + late + 0.0002, k * period, sent=3 * k)


def test_ring_buffer_keeps_the_last_chunks_in_order(tmp_path):
    t = LoopTiming(0.005, 1.0, capacity=8)
    _fill(t, 20)
    a = t.arrays()
    assert t.count == 20 and all(len(v) == 8 for v in a.values())
    assert np.allclose(a["sim"], np.arange(12, 20) * 0.005)
    assert np.all(np.diff(a["start"]) > 0)
    t.reanchors = 2
    t.write(tmp_path / "t.npz")
    back = loop_timing.load(tmp_path / "t.npz")
    assert back["count"] == 20 and back["reanchors"] == 2 and back["chunk_s"] == 0.005 and back["speedup"] == 1.0
    assert np.array_equal(back["start"], a["start"]) and np.array_equal(back["sent"], a["sent"])
    assert not list(tmp_path.glob(".*.tmp"))  # written atomically, nothing left behind


def test_begin_and_finish_record_back_to_back_chunks():
    t = LoopTiming(0.005, 2.0, capacity=4)
    t.begin(wall0=100.0, sim0=1.0, sim=1.0)
    t.finish(end=200.0, sent=7)
    t.begin(wall0=100.0, sim0=1.0, sim=1.005)  # two chunks run to catch up, one telemetry pass after them
    t.begin(wall0=100.0, sim0=1.0, sim=1.010)
    t.finish(end=300.0, sent=9)
    a = t.arrays()
    assert np.allclose(a["due"], [100.0025, 100.005, 100.0075])  # (sim + chunk - sim0) / speedup after wall0
    assert list(a["end"]) == [200.0, 300.0, 300.0] and list(a["sent"]) == [7, 9, 9]
    assert np.all(np.diff(a["start"]) >= 0)
    for _ in range(6):  # wrap the ring: only the last 4 chunks remain, all finished
        t.begin(100.0, 1.0, 2.0)
    t.finish(400.0, 11)
    assert t.count == 9 and list(t.arrays()["end"]) == [400.0] * 4


def test_summarize_on_a_known_record():
    t = LoopTiming(0.005, 1.0, capacity=1000)
    _fill(t, 101)
    a = t.arrays()
    a["start"][50] += 0.002  # one chunk 2 ms late: two spacings off by 2 ms
    s = summarize({**a, "chunk_s": 0.005, "speedup": 1.0})
    assert s["chunks"] == 101 and s["nominal_period_ms"] == pytest.approx(5.0)
    assert s["period_err_p50_ms"] == pytest.approx(0.0, abs=1e-6)
    assert s["period_err_max_ms"] == pytest.approx(2.0, abs=1e-6)
    assert s["lateness_p50_ms"] == pytest.approx(0.1, abs=1e-6)
    assert s["lateness_max_ms"] == pytest.approx(2.1, abs=1e-6)
    assert s["busy_p50_ms"] == pytest.approx(0.2, abs=1e-6)
    assert s["late_over_1ms_fraction"] == pytest.approx(1 / 101)
    assert s["sim_per_wall"] == pytest.approx(1.0, rel=1e-3)
    assert s["sent_per_wall"] == pytest.approx(600.0, rel=1e-3)
    window = summarize({**a, "chunk_s": 0.005, "speedup": 1.0}, t_from=a["start"][60], t_to=a["start"][69])
    assert window["chunks"] == 10 and window["lateness_max_ms"] == pytest.approx(0.1, abs=1e-6)
    empty = summarize({**a, "chunk_s": 0.005, "speedup": 1.0}, t_from=1e9)
    assert empty["chunks"] == 0 and math.isnan(empty["lateness_p99_ms"])
    with pytest.raises(ValueError):
        LoopTiming(0.005, 1.0, capacity=1)


def test_serve_writes_the_timing_log(tmp_path):
    path = tmp_path / "timing.npz"
    proc = subprocess.run(
        [sys.executable, "-m", "rig_emulator", "serve", "--mavlink", "tcpin:127.0.0.1:0", "--speedup", "1",
         "--duration", "0.5", "--timing-log", str(path)],
        capture_output=True, text=True, timeout=240, cwd=tmp_path)  # cwd: any state the rig keeps goes there
    assert proc.returncode == 0, proc.stderr
    log = loop_timing.load(path)
    assert log["chunk_s"] == pytest.approx(0.005) and log["speedup"] == 1.0
    assert log["count"] == len(log["start"]) == 100  # 0.5 s in 5 ms chunks
    assert np.allclose(np.diff(log["sim"]), 0.005)
    assert np.all(log["end"] >= log["start"]) and np.all(np.diff(log["start"]) > 0)
    # paced at real time, not as fast as possible: the schedule gives each 5 ms chunk at least 5 ms
    # of wall time (a re-anchor after an overrun only moves it later) and no chunk is computed
    # before its scheduled instant. (How close to real time the rig keeps up is the jitter
    # benchmark's business: a loaded machine delays the first chunks and the loop catches up.)
    assert np.all(np.diff(log["due"]) >= 0.005 - 1e-9)
    assert np.all(log["start"] >= log["due"] - 1e-6)
    assert log["start"][-1] - log["due"][0] >= 0.495 - 1e-6


def test_a_timing_log_in_a_missing_directory_is_refused_before_serving(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "rig_emulator", "serve", "--mavlink", "tcpin:127.0.0.1:0", "--duration", "0.1",
         "--timing-log", str(tmp_path / "missing" / "t.npz")],
        capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert proc.returncode == 2 and "--timing-log" in proc.stderr
    assert "serving" not in proc.stdout
