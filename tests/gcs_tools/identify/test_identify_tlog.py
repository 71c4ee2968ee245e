"""Proof of identification: a log simulated with hidden hardware-effect values (centre-of-gravity
offset, one motor's thrust gain, the sensing-to-actuation delay, joint friction), the values
recovered from the log alone by `rig-gcs identify --tlog`, a rerun resumed from the record; bad
input exits 2.

The log and the fit use different seeds: the fit does not know the log's sensor noise, turn-on
errors or load-cell offsets, as with a real rig's log. The tolerances are what that allows on a
16 s log of the shocks scenario fitted at 50 Hz:
the friction, 1.6 % of the FLC's own damping, needs both (an 8 s log at 10 Hz missed it for
four of four log seeds, by up to 0.04); with the same seed the values come back within a few
per cent.
"""

import json
import math

import pytest

from gcs_tools.cli import main
from rig_emulator.api import simulate
from rig_emulator.config.loader import load_config
from rig_emulator.link.telemetry.tlog_export import export_tlog

# hilms-ideal: this test proves the simulation method (the scenario re-simulated, --params fitted) on ideal
# physics plus the hidden effects alone; on the full hilms rig that closed-loop output-error cost is ruled by
# the noise realisation of each run, which the simulation method cannot average away. The default plant is
# identified blind by the regression method: tests/gcs_tools/identify/test_identify_regression.py.
SCENARIO, STRATEGY, DURATION, LOG_SEED, AIRFRAME = "hover-shocks", "flc", 16.0, 5, "hilms-ideal"
FIT_HZ = 50  # interval means of the logged series per second
HIDDEN_CONFIG = {"joint.cog_offset": [0.004, 0.0, 0.0], "motors.thrust_gain": [1.06, 1.0, 1.0, 1.0],
                 "control.actuation_delay": 0.006, "joint.viscous": [0.04, 0.04, 0.0]}
#: fitted key: (hidden value, bounds, tolerance: |fitted - hidden| at most this)
HIDDEN = {
    "joint.cog_offset[0]": (0.004, "-0.01:0.01", 0.0004),  # m, 10 %
    "motors.thrust_gain[0]": (1.06, "0.9:1.1", 0.02),  # the load cells' own offsets differ between seeds
    "control.actuation_delay": (0.006, "0:0.012", 0.0011),  # s: within one physics step (1 ms)
    "joint.viscous[0,1]": (0.04, "0:0.08", 0.01),  # N m s/rad, 25 %
}
PARAMS = ",".join(f"{k}={b}" for k, (_, b, _) in HIDDEN.items())
STARTS = 8  # Halton points before least_squares: delay and friction trade off near the start


@pytest.fixture(scope="module")
def hidden_log(tmp_path_factory):
    result = simulate(SCENARIO, strategy=STRATEGY, duration=DURATION, seed=LOG_SEED, airframe=AIRFRAME,
                      overrides=HIDDEN_CONFIG)
    path = tmp_path_factory.mktemp("identify") / "hidden.tlog"
    export_tlog(result, path)
    return path


def _args(log, out, record, js):
    return ["identify", "--tlog", str(log), "--scenario", SCENARIO, "--strategy", STRATEGY, "--channels",
            "attitude,load_cells", "--params", PARAMS, "--step", "control.actuation_delay=0.001", "--starts",
            str(STARTS), "--fit-hz", str(FIT_HZ), "--airframe", AIRFRAME, "-o", str(out), "--record", str(record), "--json", str(js),
            "--workers", "1", "--no-progress"]


def test_hidden_values_are_recovered_from_the_log_and_a_rerun_resumes(hidden_log, tmp_path, capsys):
    out, record, js = tmp_path / "twin.toml", tmp_path / "fit.jsonl", tmp_path / "fit.json"
    assert main(_args(hidden_log, out, record, js)) == 0
    doc = json.loads(js.read_text())
    assert doc["simulated"] > 0
    for p in doc["params"]:
        want, _, tol = HIDDEN[p["key"]]
        assert abs(p["value"] - want) <= tol, p
        assert 0 < p["sigma"] < math.inf and not p["at_bound"]
        assert abs(p["start"] - want) > tol  # started from the ideal plant's values, away from the hidden ones
    cfg = load_config(airframe=AIRFRAME, scenario=SCENARIO, files=[out])
    fitted = {p["key"]: p["value"] for p in doc["params"]}
    assert cfg["joint.cog_offset"] == [fitted["joint.cog_offset[0]"], 0.0, 0.0]
    assert cfg["joint.viscous"][:2] == [fitted["joint.viscous[0,1]"]] * 2
    text = out.read_text()
    assert "# command: rig-gcs identify --tlog" in text and "cog_offset = [" in text and "rms" in text
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
        (["--params", "vibration.blades=1:4"] + log, "integer"),
        (["--params", "control.actuation_delay=0:0.01", "--step", "control.actuation_delay=0.02"] + log, "step"),
        (log + ["--method", "simulation"], "no parameter"),
        (["--tlog", str(hidden_log), "--tlog", str(hidden_log)], "one log"),
        (["--params", "airframe.ixx=0.04:0.1", "--paper", "--paper-targets", "table7.*"], "table7.*"),
        (["--params", "airframe.ixx=0.04:0.1", "--paper-seeds", "3"] + log, "go with --paper"),
    ]
    for extra, word in cases:
        assert main(base + extra) == 2, extra
        err = capsys.readouterr().err
        assert word in err, (extra, err)
    with pytest.raises(SystemExit) as exc:  # argparse's own check
        main(base + ["--params", "airframe.ixx=0.04:0.1", "--paper", "--paper-seeds", "0"])
    assert exc.value.code == 2 and "--paper-seeds" in capsys.readouterr().err
    assert not (tmp_path / "x.toml").exists()
