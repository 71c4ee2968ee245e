"""Headless run -> .tlog -> rig-gcs errors / csv / plot, and pymavlink's tools reading the file."""

import functools
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from gcs_tools.cli import main
from gcs_tools.tlog_errors import tlog_mean_errors
from gcs_tools.tlog_read import iter_tlog
from protocol.mean_error import COLUMNS
from rig_emulator.api import simulate as _simulate
from rig_emulator.link.telemetry.tlog_export import TlogWriter, export_tlog

# these tests pin the ideal plant's behaviour (the default airframe is now the hardware rig)
simulate = functools.partial(_simulate, airframe="hilms-ideal")

MAVLOGDUMP = os.path.join(os.path.dirname(sys.executable), "mavlogdump.py")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    result = simulate("rectangle", seed=3, duration=25.0)
    path = tmp_path_factory.mktemp("tlog") / "rect.tlog"
    export_tlog(result, path)
    return result, path


def test_tlog_errors_equal_the_headless_figures(run):
    """Reference: SimResult.mean_errors() on the float64 series; the tlog's float32 fields stay within 1e-6."""
    result, path = run
    ref = result.mean_errors()
    got = tlog_mean_errors(path)
    for c in COLUMNS:
        assert got["mean_errors"][c] == pytest.approx(ref[c], abs=1e-6), c
        assert got["samples"][c] == result.series["t"].size
    window = (5.005, 20.005)  # ends between log rows: both sides select the same samples
    ref_w = result.mean_errors(window)
    got_w = tlog_mean_errors(path, *window)
    for c in COLUMNS:
        assert got_w["mean_errors"][c] == pytest.approx(ref_w[c], abs=1e-6), c


def test_errors_cli_table_json_and_exit_codes(run, tmp_path, capsys):
    _, path = run
    assert main(["errors", str(path), "--json", "--from", "2", "--to", "10"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["mean_errors"]) == set(COLUMNS) and doc["missing"] == {}
    assert main(["errors", str(path)]) == 0
    out = capsys.readouterr().out
    assert "ME_phi(deg)" in out and "ME_Z(m)" in out
    # a log with only the attitude pair: position columns missing, named
    partial = tmp_path / "att.tlog"
    w = TlogWriter(partial)
    for msg in iter_tlog(path, {"ATTITUDE", "ATTITUDE_TARGET"}):
        w.write_raw(msg.get_msgbuf(), msg._timestamp)
    w.close()
    assert main(["errors", str(partial)]) == 0
    out = capsys.readouterr().out
    assert "x_m: not computed: missing LOCAL_POSITION_NED, POSITION_TARGET_LOCAL_NED" in out
    only_pos = tmp_path / "hb.tlog"
    w = TlogWriter(only_pos)
    for msg in iter_tlog(path, {"HEARTBEAT"}):
        w.write_raw(msg.get_msgbuf(), msg._timestamp)
    w.close()
    assert main(["errors", str(only_pos)]) == 1
    assert "no mean error computable" in capsys.readouterr().err
    junk = tmp_path / "junk.tlog"
    junk.write_bytes(b"not a log at all" * 10)
    assert main(["errors", str(junk)]) == 2
    assert main(["errors", str(tmp_path / "missing.tlog")]) == 2
    assert main(["errors", str(path), "--from", "5", "--to", "1"]) == 2


def test_mavlogdump_reads_the_export(run):
    _, path = run
    ours = sum(1 for _ in iter_tlog(path))
    out = subprocess.run([sys.executable, MAVLOGDUMP, "--types", "ATTITUDE", str(path)], capture_output=True,
                         text=True, env=dict(os.environ, MAVLINK20="1"), timeout=300)
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stdout.splitlines() if "ATTITUDE" in ln]
    assert len(lines) == sum(1 for _ in iter_tlog(path, {"ATTITUDE"})) > 0
    assert ours > 10 * len(lines)


def test_csv_export(run, tmp_path):
    _, path = run
    csv_path = tmp_path / "out.csv"
    assert main(["csv", str(path), "--csv", str(csv_path), "--fields",
                 "ATTITUDE.roll,LOCAL_POSITION_NED.x,HILMS_LOAD_CELLS.thrust_n[2],NAMED_VALUE_FLOAT.LC1_N"]) == 0
    rows = csv_path.read_text().splitlines()
    assert rows[0] == ("timestamp_s,ATTITUDE.roll_rad,LOCAL_POSITION_NED.x_m,HILMS_LOAD_CELLS.thrust_n[2],"
                       "NAMED_VALUE_FLOAT.LC1_N")  # units in the names; thrust_n and LC1_N carry theirs
    last = rows[-1].split(",")
    assert all(v != "" for v in last)
    att = [m.roll for m in iter_tlog(path, {"ATTITUDE"})]
    assert float(last[1]) == att[-1]
    assert main(["csv", str(path), "--csv", str(tmp_path / "b.csv"), "--fields", "ATTITUDE.nope"]) == 2
    assert not (tmp_path / "b.csv").exists()


def test_plot_writes_pngs(run, tmp_path):
    _, path = run
    assert main(["plot", str(path), "-o", str(tmp_path / "plots")]) == 0
    for name in ("attitude", "xy_path", "position", "thrusts", "load_cells", "errors", "path_3d"):
        data = (tmp_path / "plots" / f"{name}.png").read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_simulate_out_tlog(tmp_path):
    from rig_emulator.cli import main as rig_main

    out = tmp_path / "h.tlog"
    assert rig_main(["simulate", "--scenario", "hover", "--duration", "2", "--out", str(out)]) == 0
    kinds = {m.get_type() for m in iter_tlog(out)}
    assert {"ATTITUDE", "ATTITUDE_TARGET", "LOCAL_POSITION_NED", "POSITION_TARGET_LOCAL_NED", "SERVO_OUTPUT_RAW",
            "HILMS_LOAD_CELLS", "HILMS_CONTROLLER_STATE", "SIM_STATE", "HEARTBEAT"} <= kinds
    errs = tlog_mean_errors(out)["mean_errors"]
    assert all(math.isfinite(v) for v in errs.values())
    from gcs_tools.plots import run_label_from_tlog

    assert run_label_from_tlog(out) == "scenario hover, strategy smc-flc, airframe hilms, seed 0"  # plot titles
