"""The paper's 18 numbers as targets: one evaluation of the reproduction's sweep, helix and
rectangle runs gives every number, its log residual and the claims' hinges."""

import math

import numpy as np
import pytest

from gcs_tools.identify.paper import FACTOR_2, PaperProblem, log_residual
from gcs_tools.identify.params import parse_params_arg
from gcs_tools.identify.problem import Base
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
    s = problem.summary(residuals, metrics)
    logs = np.array([row["log_residual"] for row in s["targets"]])
    assert s["rms_log_error"] == pytest.approx(float(np.sqrt(np.mean(logs ** 2))))
    assert s["within_factor_2"] == int(np.sum(np.abs(logs) <= FACTOR_2))


def test_log_residual_of_a_missing_number_is_large():
    assert log_residual(math.nan, 1.0) == log_residual(0.0, 1.0) == 4.0
    assert log_residual(2.0, 1.0) == pytest.approx(math.log(2.0))
