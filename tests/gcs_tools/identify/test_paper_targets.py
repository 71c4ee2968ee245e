"""The paper's 18 numbers as targets: one evaluation of the reproduction's sweep, helix and
rectangle runs (with the claims, its shock and extra-mass runs too) gives every number, its log
residual and the claims' hinges."""

import math

import numpy as np
import pytest

from gcs_tools.identify.paper import FACTOR_2, PaperProblem, _mass_claims, load_data, log_residual, select_targets
from gcs_tools.identify.params import parse_params_arg
from gcs_tools.identify.problem import Base
from gcs_tools.reproduce import exp_masses, exp_shocks
from gcs_tools.reproduce.experiment import REPRODUCED, Context
from gcs_tools.reproduce.metrics import hf_rms
from rig_emulator.sweep import run_jobs


@pytest.fixture(scope="module")
def evaluated():
    problem = PaperProblem(Base(), seed=0, claims=True, variant="short")
    params = parse_params_arg("motors.time_constant=0.02:0.1")
    jobs = problem.jobs(params, [0.06])
    assert all(dict(j.overrides)["motors.time_constant"] == 0.06 for j in jobs)
    results = run_jobs(jobs, workers=1)
    return problem, results, problem.evaluate(results)


def test_every_number_is_computed_from_the_experiments(evaluated):
    problem, results, (residuals, metrics) = evaluated
    assert len(problem.residual_names()) == residuals.size == 18 + len(problem.claims)
    for t, r in zip(problem.targets, residuals):
        assert math.isfinite(metrics[t.metric]) and metrics[t.metric] > 0, t.metric
        assert r == pytest.approx(math.log(metrics[t.metric] / t.value))
    helix = {r.job.strategy: r for r in results if r.job.label.startswith("helix/")}
    assert metrics["table6.flc.x_m"] == helix["flc"].mean_errors()["x_m"]
    sweep = [r for r in results if r.job.label.startswith("sweep/smc/")]
    assert len(sweep) == 7
    assert metrics["table4.smc.phi_deg"] == pytest.approx(np.mean([r.mean_errors()["phi_deg"] for r in sweep]))
    hinges = residuals[18:]
    assert np.all(hinges >= 0)
    assert len(hinges) == 12
    s = problem.summary(residuals, metrics)
    logs = np.array([row["log_residual"] for row in s["targets"]])
    assert s["rms_log_error"] == pytest.approx(float(np.sqrt(np.mean(logs ** 2))))
    assert s["within_factor_2"] == int(np.sum(np.abs(logs) <= FACTOR_2))


def test_the_shock_and_mass_claims_read_the_runs_as_the_reproduction_does(evaluated, tmp_path):
    problem, results, (residuals, metrics) = evaluated
    shocks = [r for r in results if r.job.label.startswith("shocks/")]
    masses = [r for r in results if r.job.label.startswith("masses/")]
    assert [r.job.strategy for r in shocks] == ["smc", "flc"] and len(masses) == 8
    by = {r.job.strategy: r for r in shocks}
    chatter = {s: hf_rms(r.series["t"], np.degrees(r.series["euler"] - r.series["euler_des"])[:, :2],
                         exp_shocks.CUTOFF_HZ) for s, r in by.items()}  # the roll and pitch errors, as Fig. 12 plots
    assert metrics["claim.shocks_flc_over_smc_chattering"] == pytest.approx(chatter["flc"] / chatter["smc"])
    hinge = dict(zip(problem.residual_names(), residuals))
    ctx = Context(seed=0, quick=False, out_dir=tmp_path)
    shock_section = exp_shocks.analyse(ctx, shocks)
    verdicts = {v.claim: v.status for v in shock_section.verdicts}
    verdicts.update({v.claim: v.status for v in exp_masses.analyse(ctx, masses).verdicts})
    settled = shock_section.numbers
    for claim in ("flc_no_chattering", "flc_less_overshoot", "flc_smoother_extra_mass", "smc_holds_extra_mass",
                  "smc_settles_faster"):
        if claim == "smc_settles_faster" and not all(
                math.isfinite(settled[s]["median_settling_s"]) for s in ("smc", "flc")):
            continue  # the fit counts an unsettled shock as its window, the verdict as never: compared when both settle
        assert (hinge[f"claim {claim}"] == 0.0) == (verdicts[claim] == REPRODUCED), claim


def test_log_residual_of_a_missing_number_is_large():
    assert log_residual(math.nan, 1.0) == log_residual(0.0, 1.0) == 4.0
    assert log_residual(2.0, 1.0) == pytest.approx(math.log(2.0))


def test_a_selection_of_the_numbers_is_fitted_alone():
    targets, _ = load_data()
    position = [t.metric for t in select_targets(targets, "position")]
    assert position == ["table6.flc.x_m", "table6.flc.y_m", "table6.flc.z_m", "table6.smc-flc.x_m",
                        "table6.smc-flc.y_m", "table6.smc-flc.z_m", "fig19.x_m", "fig19.y_m"]
    assert [t.metric for t in select_targets(targets, "fig19.*, table4.smc.*")] == [
        "table4.smc.phi_deg", "table4.smc.theta_deg", "fig19.x_m", "fig19.y_m"]  # in the file's order
    assert len(select_targets(targets, None)) == len(select_targets(targets, "position,attitude")) == 18
    with pytest.raises(ValueError, match="table6.flc.q_m"):
        select_targets(targets, "position,table6.flc.q_m")
    problem = PaperProblem(Base(), targets="table6.*.z_m")
    assert problem.residual_names() == ["table6.flc.z_m", "table6.smc-flc.z_m"]
    assert problem.residuals({"table6.flc.z_m": 0.2279, "table6.smc-flc.z_m": 2 * 0.2263}) == pytest.approx(
        [0.0, math.log(2.0)])


def test_several_seeds_give_the_mean_of_their_numbers():
    both = PaperProblem(Base(), seed=0, seeds=2, variant="short", targets="position")
    jobs = both.jobs([], [])
    n = len(jobs) // 2
    assert [j.seed for j in jobs] == [0] * n + [1] * n
    per_seed = []
    for seed in (0, 1):
        one = PaperProblem(Base(), seed=seed, variant="short")
        assert one.jobs([], []) == jobs[seed * n:(seed + 1) * n]  # the same runs
        per_seed.append(one.metrics(run_jobs(one.jobs([], []), workers=1)))
    assert per_seed[0]["table6.flc.z_m"] != per_seed[1]["table6.flc.z_m"]  # another seed, other noise
    merged = both.metrics(run_jobs(jobs, workers=1))
    for k in per_seed[0]:
        assert merged[k] == pytest.approx(0.5 * (per_seed[0][k] + per_seed[1][k])), k
    assert len(both.residuals(merged)) == 8
    assert both.context()["seeds"] == 2 and "seeds" not in PaperProblem(Base()).context()


class _Job:
    def __init__(self, label, strategy, overrides=()):
        self.label, self.strategy, self.overrides = label, strategy, overrides


class _Run:
    """A stand-in for an extra-mass run: what exp_masses.per_mass and summarise read."""

    def __init__(self, mass_g, strategy, chatter, diverge_at=None):
        self.job = _Job(f"masses/{strategy}/{mass_g:g}g", strategy,
                        (("disturbance.extra_masses", [{"mass": mass_g / 1000.0}]),))
        t = np.arange(0.0, 4.0, 0.002)
        # 50 Hz chattering of rms `chatter` deg in the roll and of rms `chatter` V on the motors
        roll = math.radians(chatter * 2.0) * np.sin(2 * math.pi * 50.0 * t)  # roll and pitch together: rms chatter
        if diverge_at is not None:
            roll[t >= diverge_at] = math.radians(60.0)
        euler = np.column_stack([roll, np.zeros_like(t), np.zeros_like(t)])
        v = 11.7 + chatter * math.sqrt(2.0) * np.sin(2 * math.pi * 50.0 * t)
        self.series = {"t": t, "euler": euler, "euler_des": np.zeros_like(euler), "euler_true": euler,
                       "v_cmd": np.column_stack([v] * 4)}


def test_the_extra_mass_claims_count_a_lost_mass_as_the_reproduction_does():
    held = [_Run(40, "smc", 0.4), _Run(40, "flc", 0.1), _Run(100, "smc", 0.5), _Run(100, "flc", 0.2)]
    m = _mass_claims(held)
    assert m["claim.masses_flc_over_smc_chattering"] == pytest.approx(0.4, rel=1e-3)  # the worse mass, 0.2 / 0.5
    assert m["claim.masses_smc_diverged"] == 0.0
    smc_lost = held[:2] + [_Run(100, "smc", 0.5, diverge_at=2.0), _Run(100, "flc", 0.9)]
    m = _mass_claims(smc_lost)
    assert m["claim.masses_flc_over_smc_chattering"] == pytest.approx(0.25, rel=1e-3)  # the lost mass counts 0
    assert m["claim.masses_smc_diverged"] == 1.0
    flc_lost = held[:2] + [_Run(100, "smc", 0.5), _Run(100, "flc", 0.2, diverge_at=2.0)]
    assert math.isnan(_mass_claims(flc_lost)["claim.masses_flc_over_smc_chattering"])
    _, claims = load_data()
    smoother = next(c for c in claims if c.claim == "flc_smoother_extra_mass")
    assert smoother.residual(math.nan) == log_residual(math.nan, 1.0)  # a lost FLC is the missing residual
    # a lost FLC is missing wherever it comes in the list
    assert math.isnan(_mass_claims(flc_lost[2:] + held[:2])["claim.masses_flc_over_smc_chattering"])
