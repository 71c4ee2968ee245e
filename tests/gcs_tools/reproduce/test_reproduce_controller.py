"""rig-gcs reproduce --controller: a plug-in next to the paper's four controllers on every experiment
it can fly, over the seeds, with figures, tables with the seed spread, verdicts and the runs saved;
the verdict rule on numbers made up for it; a plug-in that fails on one experiment is named with the
way around it."""

import contextlib
import io
import json
import math

import pytest

from gcs_tools.cli import main as gcs_main
from gcs_tools.errors import OperationError, UsageError
from gcs_tools.reproduce import compare
from gcs_tools.reproduce.compare import BETTER, SAME, WORSE, verdict
from gcs_tools.reproduce.compare_figures import FILES
from gcs_tools.reproduce.runner import reproduce
from rig_emulator.controllers.examples.hover import LevelHover

LQR = "rig_emulator.controllers.examples.lqr:LQRAttitude"
PID = "rig_emulator.controllers.examples.pid:PID"


class NeedsAPosition(LevelHover):
    """LevelHover that stops where the scenario gives no position reference (the attitude-only experiments)."""

    def update(self, t, obs):
        if not all(math.isfinite(x) for x in obs.reference.position):
            raise RuntimeError("no position reference")
        return super().update(t, obs)


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    """The command as a user types it, on short runs (--quick), one plant, two seeds, two plug-ins."""
    out = tmp_path_factory.mktemp("compare")
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        code = gcs_main(["reproduce", "-o", str(out), "--quick", "--workers", "1", "--no-progress", "--plant", "hilms",
                         "--seeds", "2", "--controller", PID, "--controller", LQR])
    assert code == 0
    return out, stdout.getvalue()


def test_the_report_puts_the_plugins_next_to_the_paper_controllers_on_every_experiment(compared):
    out, _ = compared
    report = (out / "report.md").read_text()
    assert "| claim of the paper |" not in report and "0 (0) of 0" not in report  # not the reproduction's claims
    for exp in compare.EXPERIMENTS:
        title, where = compare.TITLES[exp]
        body = report.split(f". {title} ({where})")[1].split("\n## ")[0]
        table = [line for line in body.splitlines() if line.startswith("| ")]
        names = [line.split(" | ")[0][2:] for line in table[1:]]
        assert names == ["SMC", "FLC", "SMC-FLC", "PID", "**PID (yours)**", "**LQRAttitude (yours)**"], exp
        # every cell a number over the two seeds with its spread, or a failed run said as such
        for line in table[1:]:
            for c in line.strip(" |").split(" | ")[1:]:
                assert c.startswith("failed") or "(" in c, (exp, line)
        assert f"![{where}, every controller]({FILES[exp]})" in body


def test_the_verdicts_compare_every_metric_with_each_paper_controller(compared):
    out, stdout = compared
    report = (out / "report.md").read_text()
    verdicts = report.split("## Verdicts")[1].split("\n## ")[0]
    assert "| metric | vs SMC | vs FLC | vs SMC-FLC | vs PID |" in verdicts
    n_metrics = sum(len(m) for m in compare.METRICS.values())
    rows = [line for line in verdicts.splitlines() if line.startswith("| Fig.") or line.startswith("| Eq.")]
    assert len(rows) == 2 * n_metrics  # both plug-ins
    cells = [c for line in rows for c in line.strip(" |").split(" | ")[1:]]
    assert {c.split(" (")[0].strip("*") for c in cells} <= {BETTER, WORSE, SAME} and len(cells) == 2 * n_metrics * 4
    # the PID plug-in against the built-in PID, the same law: its means are theirs ("1.00x", counts side by side)
    pid = [line.strip(" |").split(" | ")[4] for line in rows[:n_metrics]]
    assert all(c in ("same (1.00x)", "same (1 vs 1)", "same (5 vs 5)") for c in pid), pid
    assert compare.RULE in report
    doc = json.loads((out / "results.json").read_text())["comparison"]
    v = doc["plants"]["hilms"]["verdicts"][PID]
    assert set(v) == {"smc", "flc", "smc-flc", "pid"} and len(v["smc"]) == n_metrics
    # the PID plug-in is the built-in PID strategy's law: on the same runs it is "same" as PID on most metrics
    assert sum(x == SAME for x in v["pid"].values()) >= n_metrics // 2
    assert "PID (yours) on hilms vs SMC: better on" in stdout and "claims reproduced" not in stdout
    wrote = [line for line in stdout.splitlines() if line.startswith("wrote")][0]
    assert wrote.endswith(f"{2 * len(FILES)} figures")


def test_figures_and_runs_are_written_for_every_seed(compared):
    out, _ = compared
    for name in FILES.values():
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (out / "runs" / "hilms-seed1" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for seed in (0, 1):
        m = json.loads((out / "runs" / f"hilms-seed{seed}" / "metrics.json").read_text())
        assert m["seed"] == seed and set(m["metrics"]) == set(compare.EXPERIMENTS)
        assert set(m["metrics"]["helix"]) == {"smc", "flc", "smc-flc", "pid", PID, LQR}
        assert len(m["runs"]) == 6 * (1 + 1 + 2 + 1 + 1 + 1)  # quick: two sweep frequencies, one mass
    doc = json.loads((out / "results.json").read_text())["comparison"]["plants"]["hilms"]
    x = doc["metrics"]["helix"][PID]["x_m"]
    assert len(x["per_seed"]) == 2 and x["min"] <= x["mean"] <= x["max"] and x["per_seed"][0] != x["per_seed"][1]
    # the fidelity check is of the paper's own controllers only
    assert {r["number"].split(" ME")[0] for r in doc["fidelity"]} == {"Table 4 SMC", "Table 4 FLC", "Table 6 FLC",
                                                                      "Table 6 SMC-FLC", "Fig. 19 SMC-FLC"}


def test_the_verdict_rule_on_made_up_numbers():
    # ranges apart and means more than 5 % apart: better / worse
    assert verdict([1.0, 1.1, 1.05], [2.0, 2.1, 2.2], atol=0.001) == BETTER
    assert verdict([2.0, 2.1, 2.2], [1.0, 1.1, 1.05], atol=0.001) == WORSE
    # means apart but the seed ranges overlap: within the spread, same
    assert verdict([1.0, 2.0], [1.5, 1.6], atol=0.001) == SAME
    assert verdict([1.0, 1.2, 1.9], [1.8, 2.0, 2.1], atol=0.001) == SAME
    # one seed: no spread, the 5 % and the resolution decide
    assert verdict([1.0], [1.04], atol=0.001) == SAME
    assert verdict([1.0], [1.06], atol=0.001) == BETTER
    assert verdict([0.0001], [0.0003], atol=0.001) == SAME  # below the metric's resolution
    # higher is better (masses held, waypoints reached)
    assert verdict([4, 4], [2, 2], atol=0.5, higher_is_better=True) == BETTER
    assert verdict([2, 2], [4, 4], atol=0.5, higher_is_better=True) == WORSE
    # a failed run (inf) is worse than any finished one; as many failed: the finished seeds decide
    assert verdict([math.inf, 1.0], [5.0, 5.0], atol=0.001) == WORSE
    assert verdict([1.0, 1.0], [math.inf, 9.0], atol=0.001) == BETTER
    assert verdict([math.inf, 1.0], [math.inf, 3.0], atol=0.001) == BETTER
    assert verdict([math.inf], [math.inf], atol=0.001) == SAME


def test_spread_of_a_metric_over_the_seeds():
    s = compare.spread([1.0, 2.0, 3.0])
    assert (s["mean"], s["min"], s["max"], s["n"], s["failed"]) == (2.0, 1.0, 3.0, 3, 0)
    assert s["std"] == pytest.approx(math.sqrt(2.0 / 3.0))
    s = compare.spread([1.0, math.inf])
    assert math.isinf(s["mean"]) and s["failed"] == 1


def test_only_picks_the_experiments_compared_and_refuses_the_others(tmp_path):
    with pytest.raises(UsageError, match="--only altitude: not compared with --controller"):
        reproduce(tmp_path / "a", quick=True, workers=1, show_progress=False, controller=PID, only=["altitude"])
    with pytest.raises(UsageError, match="given twice"):
        reproduce(tmp_path / "b", quick=True, workers=1, show_progress=False, controller=[PID, PID])
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_unloadable_controller_is_a_usage_error(tmp_path):
    with pytest.raises(UsageError, match="--controller: controller nope.mod:X: cannot import"):
        reproduce(tmp_path, quick=True, workers=1, show_progress=False, controller="nope.mod:X")


def test_a_refused_plugin_parameter_is_a_usage_error_before_anything_runs(tmp_path):
    with pytest.raises(UsageError, match=r"--controller: .*unknown parameter 'controller.params.kq'"):
        reproduce(tmp_path, quick=True, workers=1, show_progress=False, controller=LQR,
                  overrides={"controller.params.kq": 1.0})
    assert not (tmp_path / "report.md").exists()


def test_a_plugin_that_raises_on_one_experiment_is_reported_and_the_comparison_goes_on(tmp_path, capsys):
    name = "tests.gcs_tools.reproduce.test_reproduce_controller:NeedsAPosition"
    code = gcs_main(["reproduce", "-o", str(tmp_path), "--quick", "--workers", "1", "--no-progress", "--plant", "hilms",
                     "--controller", name, "--only", "harmonic,helix"])
    assert code == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if line.startswith("warning:")]
    assert [w.split(", harmonic: ")[0] for w in warned] == [f"warning: {name} raised on hilms, seed {s}" for s in range(3)]
    assert all("RuntimeError: no position reference" in w for w in warned)
    report = (tmp_path / "report.md").read_text()
    said = report.split("## Runs that raised")[1].split("\n## ")[0]
    listed = [line for line in said.splitlines() if line.startswith("- ")]
    assert [line.split(", harmonic: ")[0] for line in listed] == [
        f"- **NeedsAPosition (yours)** on `hilms`, seed {s}" for s in range(3)]
    assert all("RuntimeError: no position reference" in line for line in listed)

    def row(exp):  # the plug-in's row of the experiment's table
        title, where = compare.TITLES[exp]
        body = report.split(f". {title} ({where})")[1].split("\n## ")[0]
        return next(line for line in body.splitlines() if line.startswith("| **NeedsAPosition (yours)**"))

    assert set(row("harmonic").strip(" |").split(" | ")[1:]) == {"failed (3/3)"}
    helix = dict(zip([m.key for m in compare.METRICS["helix"]], row("helix").strip(" |").split(" | ")[1:]))
    assert all(helix[k][0].isdigit() for k in ("x_m", "y_m", "z_m"))  # flown and measured (LevelHover sets no attitude)
    results = json.loads((tmp_path / "results.json").read_text())["comparison"]
    assert [(r["seed"], r["run"].split(": ")[0]) for r in results["raised"]] == [(s, "harmonic") for s in range(3)]
    ver = results["plants"]["hilms"]["verdicts"][name]["smc"]
    assert ver["harmonic/phi_deg"] == WORSE and ver["helix/x_m"] in (BETTER, SAME, WORSE)
    runs = json.loads((tmp_path / "runs" / "hilms-seed0" / "metrics.json").read_text())["runs"]
    assert [r["label"] for r in runs if "raised" in r] == [f"controller/harmonic/{name}"]


def test_a_paper_controller_that_raises_still_stops_the_comparison(tmp_path, monkeypatch):
    from gcs_tools.reproduce import runner
    from rig_emulator.sweep import JobFailed

    def one_fails(jobs, **kw):
        assert kw["keep_failed"]
        return [JobFailed(j, "RuntimeError: emulator bug") if j.strategy == "flc" and not j.controller else None
                for j in jobs]

    monkeypatch.setattr("rig_emulator.sweep.run_jobs", one_fails)
    with pytest.raises(OperationError, match="emulator bug"):
        runner.reproduce(tmp_path, quick=True, workers=1, show_progress=False, controller=PID, plants=("hilms",),
                         seeds=1, only=["harmonic"])
