"""The paper fit judged fairly: every value of the `hilms` plant has a source, the paper's numbers and
claims are marked fitted / set by hand against / predicted from those sources, the paper's physical
priors join the fit as a Gaussian penalty, and the leave-one-group-out machinery fits on some of the
paper's groups and scores the others. Cheap: no simulation runs (stand-ins for the fit and the sweep)."""

import math
import re
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from gcs_tools.cli import build_parser
from gcs_tools.identify import held_out, paper_priors, provenance
from gcs_tools.identify.cli import build
from gcs_tools.identify.fit import Evaluator, identify
from gcs_tools.identify.paper import load_data
from gcs_tools.identify.params import make_param, parse_params_arg
from gcs_tools.identify.problem import Base
from gcs_tools.identify.record import Record
from gcs_tools.reproduce.paper_data import CLAIMS
from rig_emulator.config.loader import flatten

PRESETS = Path(__file__).resolve().parents[3] / "rig_emulator" / "presets"


def _preset_keys() -> set:
    hw = flatten(tomllib.loads((PRESETS / "hardware" / "hilms.toml").read_text()))
    frame = tomllib.loads((PRESETS / "airframes" / "hilms-ideal.toml").read_text())
    return set(hw) | {f"airframe.{k}" for k in frame}


def test_every_value_of_the_hilms_plant_has_a_source_and_nothing_else_is_listed():
    sources = provenance.load_sources()
    assert {s.key for s in sources} == _preset_keys()
    assert provenance.unmatched_patterns(sources) == []  # no pattern that names no number or claim
    for s in sources:
        assert s.source.strip(), s.key
        if s.kind == "fitted":
            assert s.command.startswith("rig-gcs identify --paper"), s.key


def test_the_preset_file_says_each_fitted_value_s_command_and_each_key_s_kind():
    text = (PRESETS / "hardware" / "hilms.toml").read_text()
    flat = " ".join(line.lstrip("#").strip() for line in text.splitlines())
    for s in provenance.fitted_keys():
        assert " ".join(s.command.split()) in " ".join(flat.split()), s.key
    # every key line of the preset, or the comment block just above it, names its kind
    lines = text.splitlines()
    for i, line in enumerate(lines):
        m = re.match(r"^([a-z_A-Z0-9]+)\s*=", line)
        if not m:
            continue
        j = i
        block = [line]
        while j > 0 and lines[j - 1].startswith("#"):
            j -= 1
            block.append(lines[j])
        assert re.search(r"\b(paper|fitted|chosen|datasheet)\b", " ".join(block)), line


def _src(key, kind="chosen", fitted=(), chosen=()):
    return provenance.Source(key, kind, "why", "rig-gcs identify --paper ..." if kind == "fitted" else "",
                             tuple(fitted), tuple(chosen))


def test_marks_follow_the_sources():
    sources = [_src("a.fit", "fitted", fitted=["table4.*"], chosen=["claim:*"]),
               _src("b.hand", chosen=["table6.*.z_m", "claim:smc_settles_faster"]),
               _src("c.physics")]
    marks = provenance.marks(sources)
    assert set(marks) == set(provenance.names())
    assert len(marks) == 18 + len(CLAIMS) == 34
    assert marks["table4.smc.phi_deg"].status == provenance.FITTED
    assert marks["table4.smc.phi_deg"].keys == ("a.fit",)
    z = marks["table6.flc.z_m"]
    assert z.status == provenance.CHOSEN and z.hand == ("b.hand",) and "b.hand" in z.text()
    assert marks["table6.flc.x_m"].status == provenance.PREDICTED and "predicted" in marks["table6.flc.x_m"].text()
    assert marks["claim:smc_settles_faster"].hand == ("a.fit", "b.hand")
    c = provenance.counts(marks)
    assert c["numbers"] == {provenance.FITTED: 4, provenance.CHOSEN: 2, provenance.PREDICTED: 12}
    assert c["claims"][provenance.CHOSEN] == len(CLAIMS)
    # with nothing set against the paper, everything is predicted
    assert {m.status for m in provenance.marks([_src("c.physics")]).values()} == {provenance.PREDICTED}


def test_a_bad_sources_file_is_refused_naming_the_value():
    with pytest.raises(ValueError, match="x.y: a fitted value needs"):
        provenance.load_sources('[[value]]\nkey = "x.y"\nkind = "fitted"\nsource = "s"\n')
    with pytest.raises(ValueError, match="kind 'guess'"):
        provenance.load_sources('[[value]]\nkey = "x.y"\nkind = "guess"\nsource = "s"\n')
    with pytest.raises(ValueError, match="listed twice: x.y"):
        provenance.load_sources('[[value]]\nkey = "x.y"\nkind = "paper"\nsource = "s"\n' * 2)


def test_the_shipped_marks_name_the_fitted_keys_of_the_report():
    marks = provenance.marks()
    assert marks["table4.flc.phi_deg"].keys == ("control.actuation_delay",)
    assert marks["fig19.y_m"].keys == ("flc.position_rate_share",)
    assert marks["table6.smc-flc.psi_deg"].keys == ("motor_field.ripple_uT",)
    sentence = provenance.summary_sentence(marks)
    for s in provenance.fitted_keys():
        assert f"`{s.key}` fitted to" in sentence


def test_the_paper_priors_attach_to_the_keys_the_paper_speaks_of():
    params = parse_params_arg("joint.coulomb[0,1]=0:0.08,motors.thrust_bias_grf=-100:20,flc.position_rate_share=0:1")
    out, used = paper_priors.apply(params)
    by = {p.name: p for p in out}
    assert by["joint.coulomb[0,1]"].prior == (0.0, 0.01)
    assert by["motors.thrust_bias_grf"].prior == (0.0, 10.0)
    assert by["flc.position_rate_share"].prior is None
    assert [name for name, _ in used] == ["joint.coulomb[0,1]", "motors.thrust_bias_grf"]
    # an explicit prior wins
    mine = [make_param("joint.coulomb[0]", 0, 0.08, prior=[0.05, 0.02])]
    assert paper_priors.apply(mine)[0][0].prior == (0.05, 0.02)
    assert paper_priors.apply(params, explicit={"joint.coulomb[0,1]"})[0][0].prior is None


def test_the_prior_is_a_gaussian_penalty_in_the_cost():
    (p,) = paper_priors.apply(parse_params_arg("motors.thrust_bias_grf=-100:20"))[0]
    ev = Evaluator(None, [p], Record(None, "ctx"))
    assert ev.prior_residuals([-50.0]) == pytest.approx([-5.0])  # (value - 0) / 10 gr.F
    assert ev.prior_residuals([0.0]) == pytest.approx([0.0])


def _args(*extra):
    return build_parser().parse_args(["identify", "--paper", "-o", "x.toml", *extra])


def test_identify_paper_applies_the_priors_unless_told_not_to():
    args = _args("--params", "joint.coulomb[0,1]=0:0.08,control.actuation_delay=0.006:0.02")
    _, params, _ = build(args)
    assert {p.name: p.prior for p in params} == {"joint.coulomb[0,1]": (0.0, 0.01), "control.actuation_delay": None}
    args = _args("--params", "joint.coulomb[0,1]=0:0.08", "--no-paper-priors")
    _, params, _ = build(args)
    assert params[0].prior is None
    args = _args("--params", "joint.coulomb[0,1]=0:0.08", "--prior", "joint.coulomb[0,1]=0.04+-0.01")
    _, params, _ = build(args)
    assert params[0].prior == (0.04, 0.01)


def test_held_out_options_are_checked():
    from gcs_tools.errors import UsageError

    with pytest.raises(UsageError, match="--held-out chooses"):
        build(_args("--params", "flc.position_rate_share=0:1", "--held-out", "logo", "--paper-targets", "fig19.*"))


def test_splits_cover_the_paper_s_groups():
    logo = held_out.splits("logo")
    assert logo == [(("table6", "fig19"), ("table4",)), (("table4", "fig19"), ("table6",)),
                    (("table4", "table6"), ("fig19",))]
    assert held_out.splits("single") == [(("table4",), ("table6", "fig19")), (("table6",), ("table4", "fig19")),
                                         (("fig19",), ("table4", "table6"))]
    with pytest.raises(ValueError):
        held_out.splits("all")


# -- the leave-one-group-out machinery on a toy model: each group's numbers are the paper's times
#    exp(slope * (x - truth)), a different truth per group, so a fit on one group mispredicts the others


TRUTH = {"table4": 0.3, "table6": 0.5, "fig19": 0.8}


def _toy_metrics(x: float) -> dict:
    targets, _ = load_data()
    return {t.metric: t.value * math.exp(3.0 * (x - TRUTH[held_out.group_of(t.metric)])) for t in targets}


def _toy_identify(problem, params, *, record, **kw):
    """A stand-in for fit.identify: the grid value that minimises the problem's residuals, through the
    shared record (so the test sees what the splits share)."""
    (p,) = params
    assert p.start == pytest.approx(0.5 * (p.lo + p.hi))  # mid-range, not the shipped value
    best = None
    for x in np.linspace(p.lo, p.hi, 101):
        pt = {p.name: float(x)}
        ev = record.get(pt)
        if ev is None:
            from gcs_tools.identify.record import Evaluation

            m = _toy_metrics(float(x))
            ev = Evaluation(pt, problem.residuals(m), m)
            record.add(ev)
        cost = float(ev.residuals @ ev.residuals)
        if best is None or cost < best[0]:
            best = (cost, float(x), ev)
    return SimpleNamespace(values=[best[1]], sigma=[0.01], metrics=best[2].metrics, status="ok", evaluations=101)


def test_leave_one_group_out_fits_on_the_others_and_scores_the_held_out_group():
    params = parse_params_arg("flc.position_rate_share=0:1")
    doc = held_out.run(Base(), params, mode="logo", identify=_toy_identify,
                       evaluate=lambda problem, workers: _toy_metrics(0.46))
    fits = {tuple(s["fit_on"]): s for s in doc["splits"]}
    assert set(fits) == {("table6", "fig19"), ("table4", "fig19"), ("table4", "table6"),
                         ("table4", "table6", "fig19")}
    # Table 4 alone (truth 0.3) held out: the fit on Table 6 + Fig. 19 lands between 0.5 and 0.8, weighted
    s = fits[("table6", "fig19")]
    assert 0.5 < s["values"]["flc.position_rate_share"] < 0.8
    assert s["held_out"]["n"] == 4 and s["in_sample"]["n"] == 14
    x = s["values"]["flc.position_rate_share"]
    assert s["held_out"]["rms_log_error"] == pytest.approx(3.0 * (x - 0.3), abs=1e-9)
    assert s["held_out"]["rms_log_error"] > s["in_sample"]["rms_log_error"]
    # every number held out once: 18 pooled predictions; the fit on all three has none
    assert doc["pooled_held_out"]["n"] == 18
    assert fits[("table4", "table6", "fig19")]["held_out"]["n"] == 0
    # the splits share their points: 101 grid points, evaluated once for all four fits
    assert doc["evaluated_points"] == 101
    assert doc["shipped"]["all"]["n"] == 18
    md = held_out.markdown(doc, "rig-gcs identify --paper --held-out logo")
    assert "| Table 6 + Fig. 19 | Table 4 |" in md and "held-out rms log error" in md
    assert "table4.smc.phi_deg" in md and " h |" in md


def test_the_shared_record_gives_each_split_its_own_residuals():
    from gcs_tools.identify.paper import PaperProblem
    from gcs_tools.identify.record import Evaluation

    shared = held_out.SharedRecord()
    t4 = PaperProblem(Base(), variant="short", targets="table4.*")
    f19 = PaperProblem(Base(), variant="short", targets="fig19.*")
    m = _toy_metrics(0.3)
    shared.view(t4).add(Evaluation({"k": 0.3}, t4.residuals(m), m))
    assert shared.view(t4).get({"k": 0.3}).residuals == pytest.approx(np.zeros(4))
    r = shared.view(f19).get({"k": 0.3}).residuals
    assert r.size == 2 and np.all(r < 0)  # Fig. 19's truth is 0.8: under the paper at 0.3
    assert shared.view(f19).get({"k": 0.4}) is None


class _CountingProblem:
    """A cheap problem for the real fit.identify: residual x - target; counts the sweeps it is asked for."""

    kind = "toy"

    def __init__(self, target):
        self.target = target

    def configs(self):
        return [{"flc.position_rate_share": 0.9}]

    def context(self):
        return {"toy": self.target}

    def jobs(self, params, values):
        return [SimpleNamespace(x=values[0])]

    def residuals(self, metrics):
        return np.array([metrics["x"] - self.target])

    def evaluate(self, results):
        m = {"x": results[0].x}
        return self.residuals(m), m

    def summary(self, residuals, metrics):
        return {}


def test_the_real_fit_reuses_points_another_split_simulated(monkeypatch):
    import rig_emulator.sweep

    sims = []

    def fake_run_jobs(jobs, **kw):
        sims.extend(jobs)
        return list(jobs)

    monkeypatch.setattr(rig_emulator.sweep, "run_jobs", fake_run_jobs)
    params = held_out.mid_starts(parse_params_arg("flc.position_rate_share=0:1"))
    shared = held_out.SharedRecord()
    a = identify(_CountingProblem(0.3), params, record=shared.view(_CountingProblem(0.3)), starts=2,
                 show_progress=False, tol=1e-6)
    assert a.values[0] == pytest.approx(0.3, abs=1e-3)
    first = len(sims)
    b = identify(_CountingProblem(0.7), params, record=shared.view(_CountingProblem(0.7)), starts=2,
                 show_progress=False, tol=1e-6)
    assert b.values[0] == pytest.approx(0.7, abs=1e-3)
    # the second fit's start and Halton design (the same points) were not simulated again
    assert len(sims) - first < b.evaluations


def test_the_held_out_command_writes_the_table_as_json_and_markdown(tmp_path, monkeypatch, capsys):
    import json

    from gcs_tools.cli import main

    assert main(["identify", "--paper", "--held-out", "logo", "--params", "flc.position_rate_share=0:1",
                 "--record", str(tmp_path / "r.jsonl"), "-o", str(tmp_path / "x.json")]) == 2
    assert "drop --record" in capsys.readouterr().err

    real_run = held_out.run

    def toy_run(base, params, **kw):  # the real machinery on the toy model: no simulation
        assert kw["mode"] == "single" and kw["variant"] == "short" and kw["max_evals"] == 3
        return real_run(base, params, mode=kw["mode"], identify=_toy_identify,
                        evaluate=lambda problem, workers: _toy_metrics(0.46))

    monkeypatch.setattr(held_out, "run", toy_run)
    out = tmp_path / "held.json"
    rc = main(["identify", "--paper", "--held-out", "single", "--paper-variant", "short", "--max-evals", "3",
               "--params", "flc.position_rate_share=0:1", "--no-progress", "-o", str(out)])
    assert rc == 0
    doc = json.loads(out.read_text())
    assert [s["fit_on"] for s in doc["splits"]] == [["table4"], ["table6"], ["fig19"], ["table4", "table6", "fig19"]]
    assert doc["command"].startswith("rig-gcs identify --paper --held-out single")
    md = (tmp_path / "held.md").read_text()
    assert "| Table 4 | Table 6 + Fig. 19 |" in md and md.strip() in capsys.readouterr().out
