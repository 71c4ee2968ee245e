"""Proof of identification: a log simulated with hidden parameter values, the values recovered
from the log alone by `rig-gcs identify --tlog`, a rerun resumed from the record; bad input exits 2.

The log and the fit use different seeds: the fit does not know the log's sensor noise, turn-on
errors or load-cell offsets, as with a real rig's log.
"""

import json

import pytest

from gcs_tools.cli import main
from rig_emulator.api import simulate
from rig_emulator.config.loader import load_config
from rig_emulator.link.tlog_export import export_tlog

SCENARIO, STRATEGY, DURATION, LOG_SEED = "hover-shocks", "flc", 8.0, 5
HIDDEN = {"airframe.ixx": 0.075, "motors.time_constant": 0.08}
PARAMS = "airframe.ixx=0.04:0.1,motors.time_constant=0.02:0.12"
TOLERANCE = 0.05  # each value recovered within 5 % of the hidden one


@pytest.fixture(scope="module")
def hidden_log(tmp_path_factory):
    result = simulate(SCENARIO, strategy=STRATEGY, duration=DURATION, seed=LOG_SEED, overrides=HIDDEN)
    path = tmp_path_factory.mktemp("identify") / "hidden.tlog"
    export_tlog(result, path)
    return path


def _args(log, out, record, js):
    return ["identify", "--tlog", str(log), "--scenario", SCENARIO, "--strategy", STRATEGY, "--channels",
            "attitude,load_cells", "--params", PARAMS, "-o", str(out), "--record", str(record), "--json", str(js),
            "--workers", "1", "--no-progress"]


def test_hidden_values_are_recovered_from_the_log_and_a_rerun_resumes(hidden_log, tmp_path, capsys):
    out, record, js = tmp_path / "twin.toml", tmp_path / "fit.jsonl", tmp_path / "fit.json"
    assert main(_args(hidden_log, out, record, js)) == 0
    doc = json.loads(js.read_text())
    assert doc["simulated"] > 0
    for p in doc["params"]:
        want = HIDDEN[p["key"]]
        assert p["value"] == pytest.approx(want, rel=TOLERANCE), p
        assert 0 < p["sigma"] < 0.1 * want and not p["at_bound"]
    # starting values were the preset's, well away from the hidden ones
    assert abs(doc["params"][0]["start"] - HIDDEN["airframe.ixx"]) > 0.1 * HIDDEN["airframe.ixx"]
    cfg = load_config(scenario=SCENARIO, files=[out])
    assert cfg["airframe.ixx"] == doc["params"][0]["value"]
    text = out.read_text()
    assert "# command: rig-gcs identify --tlog" in text and "airframe.ixx = " in text and "rms" in text
    # the same command again: every point comes from the record, nothing is simulated, same answer
    capsys.readouterr()
    js2 = tmp_path / "again.json"
    assert main(_args(hidden_log, out, record, js2)) == 0
    again = json.loads(js2.read_text())
    assert again["simulated"] == 0 and again["runs"] == 0
    assert [p["value"] for p in again["params"]] == [p["value"] for p in doc["params"]]
    assert "found in the record" in capsys.readouterr().out


def test_bad_input_exits_2_naming_it(hidden_log, tmp_path, capsys):
    out = str(tmp_path / "x.toml")
    base = ["identify", "-o", out, "--no-progress"]
    log = ["--tlog", str(hidden_log), "--scenario", SCENARIO]
    garbage = tmp_path / "broken.tlog"
    garbage.write_bytes(b"\x00\x01 this is not MAVLink " * 50)
    cases = [
        (["--params", "airframe.ixxx=0.04:0.1"] + log, "did you mean 'airframe.ixx'"),
        (["--params", "airframe.ixx=-1:0.1"] + log, "airframe.ixx"),
        (["--params", "motors.time_constant=0.01:20"] + log, "[0, 10]"),
        (["--params", "airframe.ixx=0.04:0.1", "--tlog", str(garbage), "--scenario", SCENARIO], "broken.tlog"),
        (["--params", "airframe.ixx=0.04:0.1", "--tlog", str(tmp_path / "none.tlog"), "--scenario", SCENARIO],
         "none.tlog"),
        (["--params", "airframe.ixx=0.04:0.1", "--tlog", str(hidden_log)], "--scenario"),
        (["--params", "airframe.ixx=0.04:0.1", "--paper"] + log, "not both"),
        (["--params", "airframe.ixx=0.04:0.1"] + log + ["--channels", "attitude,wind"], "wind"),
        (["--params", "airframe.ixx=0.04:0.1", "--tlog", str(hidden_log), "--scenario", "nope"], "nope"),
        (["--params", "airframe.ixx=0.04:0.1", "--paper", "--set", "smc.k=[1]"], "smc.k"),
        (log, "no parameter"),
    ]
    for extra, word in cases:
        assert main(base + extra) == 2, extra
        err = capsys.readouterr().err
        assert word in err, (extra, err)
    assert not (tmp_path / "x.toml").exists()
