"""Headless runs in chunks: the same rows and figures as one whole run, files as numpy writes
them, a stop between chunks keeps what was simulated, Ctrl-C exits 130 with the file written."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.headless.series_files import CsvSeriesWriter, NpzSeriesWriter, csv_columns
from rig_emulator.headless.streamed import StreamedRun
from rig_emulator.simulation.run import Simulation

def _cfg(duration=3.0):
    return load_config(scenario="helix", overrides={"sim.duration": duration, "sim.seed": 4,
                                                     "faults.events": [{"t": 1.5, "sensor": "imu", "index": 2,
                                                                        "mode": "noise", "magnitude": 3.0}]})


class _Keep:
    def __init__(self):
        self.parts = []

    def write(self, rows):
        self.parts.append(rows.copy())


def test_chunks_give_the_rows_and_mean_errors_of_one_run():
    whole = Simulation(_cfg()).run()
    keep = _Keep()
    res = StreamedRun(_cfg(), chunk_rows=7).run([keep])  # 7 rows: chunk ends fall anywhere, a fault mid-chunk
    rows = np.concatenate(keep.parts)
    assert rows.shape == whole.log.shape and rows.tobytes() == whole.log.tobytes()
    assert res.mean_errors == whole.mean_errors() and res.rows == whole.log.shape[0]
    assert res.steps == whole.steps and not res.interrupted
    assert np.array_equal(res.reached_t, whole.reached_t, equal_nan=True)


def test_writers_produce_numpys_files(tmp_path):
    whole = Simulation(_cfg(1.0)).run()
    npz, csv = NpzSeriesWriter(tmp_path / "a.npz"), CsvSeriesWriter(tmp_path / "a.csv")
    for w in (npz, csv):
        for i in range(0, whole.log.shape[0], 30):
            w.write(whole.log[i : i + 30])
        w.commit()
    np.savez_compressed(tmp_path / "b.npz", **whole.series)
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    assert list(a.keys()) == list(b.keys())
    for k in b.keys():
        assert a[k].shape == b[k].shape and a[k].tobytes() == b[k].tobytes(), k
    cols, names = csv_columns()
    np.savetxt(tmp_path / "b.csv", whole.log[:, cols], delimiter=",", header=",".join(names), comments="", fmt="%.9g")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.npz", "b.csv", "b.npz"]  # no scratch left


def test_abort_leaves_the_old_file(tmp_path):
    out = tmp_path / "run.npz"
    out.write_bytes(b"old")
    w = NpzSeriesWriter(out)
    w.write(np.zeros((3, 62)))
    w.abort()
    assert out.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["run.npz"]


def test_stop_ends_after_the_chunk_being_simulated():
    run = StreamedRun(_cfg(), chunk_rows=50)

    class StopAfterFirst(_Keep):
        def write(self, rows):
            super().write(rows)
            run.request_stop()

    keep = StopAfterFirst()
    res = run.run([keep])
    assert res.interrupted and res.rows == 50 and len(keep.parts) == 1
    assert res.sim_time_s == pytest.approx(0.5)


def test_ctrl_c_writes_what_was_simulated_and_exits_130(tmp_path):
    out = tmp_path / "long.npz"
    p = subprocess.Popen([sys.executable, "-m", "rig_emulator", "simulate", "--scenario", "hover", "--duration",
                          "100000", "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 600
        while not any(n.endswith(".parts") for n in os.listdir(tmp_path)):  # the run has started
            assert p.poll() is None and time.monotonic() < deadline, p.communicate()
            time.sleep(0.05)
        time.sleep(0.5)
        p.send_signal(signal.SIGINT)
        stdout, stderr = p.communicate(timeout=120)
    finally:
        p.kill()
    assert p.returncode == 130, stderr
    lines = [ln for ln in stderr.splitlines() if "compil" not in ln]
    assert len(lines) == 1 and lines[0].startswith("rig-emulator: interrupted at t = "), stderr
    assert "Traceback" not in stderr and stdout == ""
    data = np.load(out)
    t = data["t"]
    assert t.size > 0 and np.allclose(t, np.arange(t.size) * 0.01, rtol=0, atol=1e-9)
    assert data["pos"].shape == (t.size, 3) and sorted(os.listdir(tmp_path)) == ["long.npz"]
