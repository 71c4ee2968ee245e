"""FLC stability analysis (Eq. 16-32): planes, the LMI of Eq. 32, R2 of Eq. 31, rig-gcs stability."""

import json
import math
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import solve_continuous_lyapunov

from gcs_tools.cli import main
from gcs_tools.stability import AnalysisUnavailable, analyse, analyse_gains, load_settings
from gcs_tools.stability import paper_values
from gcs_tools.stability.error_dynamics import g_max
from gcs_tools.stability.lmi import solve_lmi
from gcs_tools.stability.planes import fit_axis, saturation_edge
from gcs_tools.stability.ultimate_bound import r2_eq31, ultimate_bound
from rig_emulator.config.loader import ConfigError
from rig_emulator.control.fuzzy import make_axis
from rig_emulator.control.fuzzy_surface import control_surface, fit_plane

FAST = settings(max_examples=25, deadline=None)
d1s = st.floats(0.01, 2.0)


@pytest.fixture(scope="module")
def result():
    return analyse()


def _closed_loop(kappa, inertia):
    """A = N - h kappa built here from Eq. 24 and A10, independently of the package."""
    A = np.zeros((6, 6))
    for k, inertia_k in enumerate(inertia):
        kp, kd = kappa[k, 2 * k], kappa[k, 2 * k + 1]
        A[2 * k, 2 * k + 1] = 1.0
        A[2 * k + 1, 2 * k] = -kp / inertia_k
        A[2 * k + 1, 2 * k + 1] = -kd / inertia_k
    return A


# --- planes (Eq. 16-17) ---------------------------------------------------------------------------------------------

@FAST
@given(st.floats(-50, 50), st.floats(-50, 50), st.floats(0.01, 5), st.floats(0.01, 5))
def test_fit_plane_recovers_a_plane_exactly(kp, kd, e_max, de_max):
    E, DE = np.meshgrid(np.linspace(-e_max, e_max, 9), np.linspace(-de_max, de_max, 7), indexing="ij")
    got = fit_plane(E, DE, kp * E + kd * DE)
    assert got == pytest.approx((kp, kd), rel=1e-9, abs=1e-9)


@FAST
@given(d1s, d1s, d1s, st.floats(0.1, 1.0))
def test_even_geometry_surface_is_linear_and_fits_exactly(d1_e, d1_de, d1_u, scale):
    # even terms + Table 1 give u = d1_u (e/d1_e + de/d1_de) / 2 up to the saturation edge 3 d1 (RIG-SPEC oracle)
    plane = fit_axis("phi", make_axis(d1_e, d1_de, d1_u, geometry="even"), scale, 11)
    assert plane.e_max == pytest.approx(3 * d1_e * scale)
    assert plane.kp == pytest.approx(d1_u / (2 * d1_e), rel=1e-9)
    assert plane.kd == pytest.approx(d1_u / (2 * d1_de), rel=1e-9)
    assert plane.residual_max <= 1e-9 * d1_u


@FAST
@given(d1s, d1s, d1s, st.floats(0.2, 2.0))
def test_paper_geometry_gain_ratio_is_the_d1_ratio(d1_e, d1_de, d1_u, scale):
    # Table 1 is Toeplitz: u = f(e/d1_e) + f(de/d1_de), so kp d1_e = kd d1_de on a proportional rectangle
    plane = fit_axis("phi", make_axis(d1_e, d1_de, d1_u), scale, 21)
    assert plane.kp * d1_e == pytest.approx(plane.kd * d1_de, rel=1e-9)
    assert plane.kp > 0 and plane.kd > 0


def test_saturation_edge_of_the_paper_geometry():
    axis = make_axis(1.0, 2.0, 1.0)
    assert saturation_edge(axis.e_terms) == pytest.approx(1.0 + 0.8 + 1.2)  # d1 + d2 + dt
    assert saturation_edge(axis.de_terms) == pytest.approx(2.0 * 3.0)


def test_kappas_are_the_least_squares_planes_of_the_flown_surface(result):
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.params import control_params

    cp = control_params(load_config("hilms-ideal"))
    for p, axis in zip(result.planes, (cp.flc_phi, cp.flc_theta, cp.flc_psi)):
        E, DE, U = control_surface(axis, p.e_max, p.de_max, p.grid_points)
        coef, *_ = np.linalg.lstsq(np.column_stack((E.ravel(), DE.ravel())), U.ravel(), rcond=None)
        assert (p.kp, p.kd) == pytest.approx(tuple(coef), rel=1e-12)
        assert p.residual_max == pytest.approx(np.max(np.abs(U - coef[0] * E - coef[1] * DE)), rel=1e-9)
    assert result.kappa[0, 0] == result.planes[0].kp and result.kappa[2, 5] == result.planes[2].kd
    assert np.count_nonzero(result.kappa) == 6


# --- the LMI of Eq. 32 ----------------------------------------------------------------------------------------------

def test_reported_p_is_positive_definite_and_satisfies_the_lmi(result):
    assert result.feasible and result.derived.verdict == "feasible"
    P = np.array(result.to_dict()["lmi"]["derived"]["sdp"]["P"])
    assert np.allclose(P, P.T)
    assert np.linalg.eigvalsh(P).min() > 0
    A = _closed_loop(result.kappa, result.inertia)
    assert np.linalg.eigvalsh(A.T @ P + P @ A).max() < 0
    # trace-minimal P with margin 1 is the Lyapunov solution of A^T P + P A = -I
    P0 = solve_continuous_lyapunov(A.T, -np.eye(6))
    assert np.allclose(P, P0, rtol=1e-6, atol=1e-8)
    assert result.to_dict()["lmi"]["derived"]["sdp"]["P_eigenvalues"] == pytest.approx(np.linalg.eigvalsh(P).tolist())


def test_printed_eq32_is_infeasible_with_a_certificate(result):
    for form in (result.printed, result.paper_printed):
        assert form.verdict == "infeasible"
        assert {m.axis for m in form.unstable} == {"phi", "theta", "psi"}
        for m in form.unstable:
            assert m.eigenvalue.real > 0 and m.c0 < 0 and "wrong sign" in m.reason
            assert form.sdp.best_max_eigenvalue >= 2 * m.eigenvalue.real * (1 - 1e-6)
    assert result.paper_derived.verdict == "feasible"


def test_constructed_unstable_gains_are_infeasible_and_explained():
    kappa = paper_values.kappa_matrix(((9.8, -2.0), (9.8, 6.7), (6.3, 9.2)))  # negative damping on phi
    derived, printed = analyse_gains(kappa, (0.062, 0.062, 0.116))
    assert derived.verdict == "infeasible" and not derived.feasible
    assert {m.axis for m in derived.unstable} == {"phi"}
    text = derived.explanation()
    assert "phi" in text and "rate feedback" in text
    rng = np.random.default_rng(0)
    for m in derived.unstable:  # the certificate holds for any P > 0
        for _ in range(5):
            X = rng.normal(size=(6, 6))
            P = X @ X.T + 1e-3 * np.eye(6)
            v = m.vector
            assert np.real(v.conj() @ (derived.F.T @ P + P @ derived.F) @ v) >= 0
    kappa = paper_values.kappa_matrix(((-1.0, 6.7), (9.8, 6.7), (6.3, 9.2)))  # positive feedback on the angle
    derived, _ = analyse_gains(kappa, (0.062, 0.062, 0.116))
    assert derived.verdict == "infeasible" and "wrong sign" in derived.explanation()


def test_lmi_is_deterministic():
    kappa = paper_values.kappa_matrix()
    a = solve_lmi(_closed_loop(kappa, (0.062, 0.062, 0.116)), 1.0, 1e-6)
    b = solve_lmi(_closed_loop(kappa, (0.062, 0.062, 0.116)), 1.0, 1e-6)
    assert np.array_equal(a.P, b.P)


def test_paper_p_is_transcribed_and_checked(result):
    pp = result.paper_p
    assert np.allclose(pp.eig_printed, paper_values.P_EIGENVALUES, atol=1.5e-3)  # Eq. 43's list
    assert not pp.symmetric and not pp.positive_definite
    # it meets H > 0 of Eq. 32 as printed (not P > 0) and fails the derived form
    assert pp.lmi_max_eigenvalue["printed"] < 0 < pp.lmi_max_eigenvalue["derived"]


def test_missing_cvxpy_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "cvxpy", None)
    with pytest.raises(AnalysisUnavailable, match=r"pip install"):
        solve_lmi(-np.eye(2), 1.0, 1e-6)


# --- Eq. 27-31 ------------------------------------------------------------------------------------------------------

def test_r2_hand_case():
    assert r2_eq31(2.0, 3.0, 0.5, 4.0, 2.0) == pytest.approx(4.0)  # (2*3 + 0.5*4) / 2
    h = np.zeros((6, 3))
    h[1, 0] = h[3, 1] = h[5, 2] = 1.0
    b = ultimate_bound(np.eye(6), -0.5 * np.eye(6), h, np.array([0, 3.0, 0, 4.0, 0, 0]), [1.0, 0, 0], 20.0)
    assert (b.sigma_min_H, b.sigma_max_P, b.sigma_max_Ph) == pytest.approx((1.0, 1.0, 1.0))
    assert b.r2 == pytest.approx(6.0) and b.r2_derived == pytest.approx(12.0)  # (1*5 + 1*1) / 1
    assert b.ultimate_bound == pytest.approx(12.0) and b.inside_region
    with pytest.raises(ValueError):
        r2_eq31(1.0, 1.0, 1.0, 1.0, 0.0)


def test_g_max_hand_case():
    g = g_max(1.0, 1.0, 2.0, [0.0, 0.0, 0.0], [1.0, 2.0, 3.0])
    assert g.tolist() == [0.0, 6.0, 0.0, 3.0, 0.0, 0.0]  # |Iyy-Izz|/Ixx th' ps', |Izz-Ixx|/Iyy ph' ps', 0
    g = g_max(1.0, 1.0, 2.0, [1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    assert g.tolist() == [0.0, 2.0, 0.0, 2.0, 0.0, 0.0]  # desired and actual terms both count


def test_bound_uses_the_result_p(result):
    b = result.bound
    assert b.d_star_norm == pytest.approx(math.hypot(*(p.residual_max for p in result.planes)))
    assert b.sigma_max_P == pytest.approx(result.derived.sdp.p_eigenvalues[-1])
    assert b.r2 == pytest.approx((b.sigma_max_P * b.g_max_norm + b.sigma_max_Ph * b.d_star_norm) / b.sigma_min_H)


# --- settings, report, CLI ------------------------------------------------------------------------------------------

def test_settings_are_validated():
    assert load_settings().fit_scale == 1.0
    assert load_settings({"stability.fit.scale": 0.5}).fit_scale == 0.5
    with pytest.raises(ConfigError, match="fit.scale"):
        load_settings({"fit.scale": -1.0})
    with pytest.raises(ConfigError, match="unknown analysis setting"):
        load_settings({"fit.scal": 1.0})


def test_markdown_states_feasibility_and_paper_values(result):
    md = result.to_markdown()
    assert md.startswith("## FLC stability")
    assert "is **feasible**" in md and "**infeasible**" in md
    assert "9.8" in md and "0.763" in md and "R2 (Eq. 31" in md


def test_cli_json(capsys):
    assert main(["stability", "--json", "--set", "stability.fit.grid_points=21"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["feasible"] is True and doc["settings"]["fit.grid_points"] == 21
    assert len(doc["kappa"]) == 3 and doc["lmi"]["printed"]["verdict"] == "infeasible"
    assert main(["stability", "--set", "stability.fit.scale=3"]) == 2
    assert "fit.scale" in capsys.readouterr().err
