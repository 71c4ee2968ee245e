"""Tests of the FLC of Sec. 3-2 (rig_emulator/control/fuzzy.py, fuzzy_surface.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.control.fuzzy import (
    INPUT_TERMS,
    OUTPUT_TERMS,
    PAPER_RATIOS,
    RULE_TABLE,
    FuzzyAxis,
    even_input_terms,
    flc_axis,
    flc_eval,
    flc_eval_many,
    flc_eval_max,
    input_terms,
    make_axis,
    membership,
    output_centers,
    paper_input_terms,
)
from rig_emulator.control.fuzzy_surface import control_surface, fit_plane, plane_residual

SETTINGS = settings(max_examples=150, deadline=None)

scale = st.floats(1e-3, 1e3)
unit_in = st.floats(-10.0, 10.0, allow_nan=False)  # inputs in units of d1 (saturation at 3)


# ----------------------------------------------------------------------------------------
# Pure-numpy reference (independent of the compiled membership code: np.interp breakpoints)
# ----------------------------------------------------------------------------------------


def ref_memberships(x, terms):
    mu = np.empty(terms.shape[0])
    for i, (c, lw, rw, sh) in enumerate(terms):
        if sh < 0:
            mu[i] = np.interp(x, [c, c + rw], [1.0, 0.0])
        elif sh > 0:
            mu[i] = np.interp(x, [c - lw, c], [0.0, 1.0])
        else:
            mu[i] = np.interp(x, [c - lw, c, c + rw], [0.0, 1.0, 0.0])
    return mu


def ref_flc(e, de, axis, table, aggregation="sum"):
    W = np.outer(ref_memberships(de, axis.de_terms), ref_memberships(e, axis.e_terms))
    if aggregation == "sum":
        y = axis.out_centers[table]
        return 0.0 if W.sum() == 0 else float((y * W).sum() / W.sum())
    heights = np.zeros(len(axis.out_centers))
    np.maximum.at(heights, table.ravel(), W.ravel())
    return float((axis.out_centers * heights).sum() / heights.sum())


def u_of(axis, e, de):
    return flc_axis(e, de, axis, RULE_TABLE)


# ----------------------------------------------------------------------------------------
# Table 1 and geometry
# ----------------------------------------------------------------------------------------


def test_rule_table_is_table_1_and_toeplitz():
    assert RULE_TABLE.shape == (7, 7) and RULE_TABLE.dtype == np.int64
    assert not RULE_TABLE.flags.writeable
    j, i = np.indices((7, 7))
    # Output index k = (i - 3) + (j - 3) on -6..6, i.e. i + j on 0..12.
    assert np.array_equal(RULE_TABLE, i + j)
    def name(de_t, e_t):
        return OUTPUT_TERMS[RULE_TABLE[INPUT_TERMS.index(de_t), INPUT_TERMS.index(e_t)]]

    assert name("NU", "NU") == "NU" and name("PU", "PU") == "PU"
    assert name("NU", "PU") == "Z" and name("PU", "NU") == "Z"
    assert name("NB", "PU") == "PVS" and name("PS", "NB") == "NVS"
    assert name("Z", "PU") == "PM" and name("NS", "PB") == "PVS"


def test_paper_geometry_follows_reading():
    d1 = 0.03
    r1, r2, r3, r4 = PAPER_RATIOS
    t = paper_input_terms(d1)
    c = [d1, d1 + r2 * d1, d1 + r2 * d1 + r3 * d1]
    assert np.allclose(t[:, 0], [-c[2], -c[1], -c[0], 0.0, c[0], c[1], c[2]], rtol=1e-15)
    assert t[3, 1] == t[3, 2] == pytest.approx(r1 * d1)
    assert np.allclose(t[1:, 1], [r4 * d1] * 2 + [r1 * d1] + [r4 * d1] * 3)
    assert np.allclose(t[:-1, 2], [r4 * d1] * 3 + [r1 * d1] + [r4 * d1] * 2)
    assert t[0, 1] == t[-1, 2] == math.inf
    assert list(t[:, 3]) == [-1, 0, 0, 0, 0, 0, 1]
    # Shoulders: 0 at dt inside the center, 1 at and beyond it.
    assert membership(c[2] - r4 * d1, t, 6) == 0.0
    assert membership(c[2] - 0.5 * r4 * d1, t, 6) == pytest.approx(0.5)
    assert membership(c[2], t, 6) == 1.0 and membership(1e9, t, 6) == 1.0
    assert membership(-1e9, t, 0) == 1.0 and membership(1e9, t, 0) == 0.0
    assert membership(0.0, t, 3) == 1.0 and membership(r1 * d1, t, 3) == 0.0


def test_even_geometry_and_output_centers():
    t = even_input_terms(2.0)
    assert np.array_equal(t[:, 0], [-6, -4, -2, 0, 2, 4, 6])
    assert np.all(t[1:, 1] == 2.0) and np.all(t[:-1, 2] == 2.0)
    y = output_centers(0.56)
    assert y.shape == (13,) and y[6] == 0.0
    assert np.allclose(np.diff(y), 0.28) and y[-1] == pytest.approx(3 * 0.56)
    assert np.array_equal(y, -y[::-1])


def test_builders_reject_bad_geometry():
    with pytest.raises(ValueError):
        paper_input_terms(1.0, r=(0.6, 0.8, 0.6, 0.3))  # dt too small: gap between Z and PS
    with pytest.raises(ValueError):
        input_terms([0, 1, 2, 3, 3, 5, 6], [1] * 7, [1] * 7)  # centers not increasing
    with pytest.raises(ValueError):
        paper_input_terms(0.0)
    with pytest.raises(ValueError):
        output_centers(-1.0)
    with pytest.raises(ValueError):
        make_axis(1, 1, 1, geometry="odd")


# ----------------------------------------------------------------------------------------
# The evaluator
# ----------------------------------------------------------------------------------------


@SETTINGS
@given(d1e=scale, d1de=scale, d1u=scale, a=unit_in, b=unit_in)
def test_even_geometry_is_saturated_pd(d1e, d1de, d1u, a, b):
    """RIG-SPEC oracle: u = d1_u (sat3(e/d1_e) + sat3(de/d1_de)) / 2 (product + Eq. 14)."""
    axis = make_axis(d1e, d1de, d1u, geometry="even")
    e, de = a * d1e, b * d1de
    expected = d1u * (min(max(e / d1e, -3.0), 3.0) + min(max(de / d1de, -3.0), 3.0)) / 2.0
    assert u_of(axis, e, de) == pytest.approx(expected, rel=1e-12, abs=1e-12 * d1u)


@SETTINGS
@given(
    d1e=scale, d1de=scale, d1u=scale, a=unit_in, b=unit_in,
    r1=st.floats(0.3, 1.0), r2=st.floats(0.3, 1.5), r3=st.floats(0.3, 1.5), r4=st.floats(0.8, 2.0),
    geometry=st.sampled_from(["paper", "even"]),
)
def test_compiled_equals_numpy_reference(d1e, d1de, d1u, a, b, r1, r2, r3, r4, geometry):
    try:
        axis = make_axis(d1e, d1de, d1u, r=(r1, r2, r3, r4), geometry=geometry)
    except ValueError:
        return  # this r leaves a gap between terms; rejected by design (tested above)
    e, de = a * d1e, b * d1de
    expected = ref_flc(e, de, axis, RULE_TABLE)
    assert u_of(axis, e, de) == pytest.approx(expected, rel=1e-12, abs=1e-12 * d1u)
    work = np.empty(13)
    got = flc_eval_max(e, de, axis.e_terms, axis.de_terms, axis.out_centers, RULE_TABLE, work)
    assert got == pytest.approx(ref_flc(e, de, axis, RULE_TABLE, "max"), rel=1e-12, abs=1e-12 * d1u)


@SETTINGS
@given(d1e=scale, d1de=scale, d1u=scale, a=unit_in, b=unit_in)
def test_paper_geometry_is_odd(d1e, d1de, d1u, a, b):
    axis = make_axis(d1e, d1de, d1u)
    e, de = a * d1e, b * d1de
    assert u_of(axis, -e, -de) == pytest.approx(-u_of(axis, e, de), abs=1e-12 * d1u)
    work = np.empty(13)
    args = (axis.e_terms, axis.de_terms, axis.out_centers, RULE_TABLE, work)
    mirrored = -flc_eval_max(e, de, *args)
    assert flc_eval_max(-e, -de, *args) == pytest.approx(mirrored, abs=1e-12 * d1u)


def test_origin_and_corners():
    d1u = 0.56
    for geometry in ("paper", "even"):
        axis = make_axis(math.radians(1.8), math.radians(7.0), d1u, geometry=geometry)
        big = 1e3
        y = axis.out_centers
        assert abs(u_of(axis, 0.0, 0.0)) <= 1e-15 * d1u
        assert u_of(axis, big, big) == pytest.approx(y[OUTPUT_TERMS.index("PU")], rel=1e-14)
        assert u_of(axis, -big, -big) == pytest.approx(y[OUTPUT_TERMS.index("NU")], rel=1e-14)
        assert u_of(axis, -big, big) == 0.0 and u_of(axis, big, -big) == 0.0
        assert u_of(axis, math.inf, math.inf) == pytest.approx(3 * d1u, rel=1e-14)
        # Row Z, column PU (de small, e saturated): PM; with the paper geometry NS/PS of de
        # fire symmetrically about Z, so the average is still exactly the PM center.
        assert u_of(axis, big, 0.0) == pytest.approx(y[OUTPUT_TERMS.index("PM")], rel=1e-12)
        assert u_of(axis, 0.0, -big) == pytest.approx(y[OUTPUT_TERMS.index("NM")], rel=1e-12)


def test_every_rule_of_table_1_at_term_centers():
    """Even geometry: at term centers one rule fires alone and u is its consequent's center."""
    d1e, d1de = 0.5, 2.0
    axis = make_axis(d1e, d1de, 0.77, geometry="even")
    for j in range(7):
        for i in range(7):
            u = u_of(axis, (i - 3) * d1e, (j - 3) * d1de)
            assert u == pytest.approx(axis.out_centers[RULE_TABLE[j, i]], rel=1e-14, abs=1e-15)


def test_max_aggregation_differs_from_per_rule_sum():
    """e = d1/2, de = d1/4 (even): Eq. 14 gives 3/8 d1_u, max aggregation 5/14 d1_u."""
    axis = make_axis(1.0, 1.0, 1.0, geometry="even")
    work = np.empty(13)
    assert u_of(axis, 0.5, 0.25) == pytest.approx(3 / 8, rel=1e-14)
    got = flc_eval_max(0.5, 0.25, axis.e_terms, axis.de_terms, axis.out_centers, RULE_TABLE, work)
    assert got == pytest.approx(5 / 14, rel=1e-14)


@SETTINGS
@given(a1=unit_in, a2=unit_in, b=unit_in, swap=st.booleans())
def test_paper_geometry_is_monotonic(a1, a2, b, swap):
    """Non-decreasing in e for fixed de and in de for fixed e (checked numerically first)."""
    d1e, d1de, d1u = math.radians(1.8), math.radians(7.0), 0.56
    axis = make_axis(d1e, d1de, d1u)
    lo, hi = min(a1, a2), max(a1, a2)
    if swap:
        u_lo, u_hi = u_of(axis, b * d1e, lo * d1de), u_of(axis, b * d1e, hi * d1de)
    else:
        u_lo, u_hi = u_of(axis, lo * d1e, b * d1de), u_of(axis, hi * d1e, b * d1de)
    assert u_hi >= u_lo - 1e-14 * d1u


def _paper_max_slope_per_d1():
    """Largest slope of sum_i(k_i mu_i)/sum_i(mu_i) in units of 1/d1: just inside e = d0,
    where Z vanishes and PS = 1 - (d1 - d0)/dt is the only other term: 1/(r1 PS)."""
    r1, _, _, r4 = PAPER_RATIOS
    return 1.0 / (r1 * (1.0 - (1.0 - r1) / r4))


@SETTINGS
@given(a1=unit_in, a2=unit_in, b=unit_in)
def test_paper_geometry_has_bounded_slope(a1, a2, b):
    d1e, d1de, d1u = math.radians(2.5), math.radians(5.0), 0.77
    axis = make_axis(d1e, d1de, d1u)
    lip = d1u / 2.0 * _paper_max_slope_per_d1() / d1e
    du = abs(u_of(axis, a2 * d1e, b * d1de) - u_of(axis, a1 * d1e, b * d1de))
    assert du <= lip * abs(a2 - a1) * d1e * (1 + 1e-9) + 1e-14 * d1u


def test_slope_bound_is_attained_at_z_edge():
    axis = make_axis(1.0, 1.0, 2.0)
    d0 = PAPER_RATIOS[0]
    h = 1e-7
    slope = (u_of(axis, d0, 0.0) - u_of(axis, d0 - h, 0.0)) / h
    assert slope == pytest.approx(_paper_max_slope_per_d1(), rel=1e-5)


def test_axis_wrapper_and_batch_match_scalar():
    axis = make_axis(0.12, 0.30, 2.66)
    assert isinstance(axis, FuzzyAxis)
    rng = np.random.default_rng(3)
    e = rng.uniform(-0.6, 0.6, 200)
    de = rng.uniform(-1.5, 1.5, 200)
    out = np.empty(200)
    flc_eval_many(e, de, axis.e_terms, axis.de_terms, axis.out_centers, RULE_TABLE, out)
    for n in range(200):
        assert out[n] == flc_eval(e[n], de[n], *axis, RULE_TABLE)


# ----------------------------------------------------------------------------------------
# Surface analysis (Eq. 16-17)
# ----------------------------------------------------------------------------------------


@SETTINGS
@given(kp=st.floats(-50, 50), kd=st.floats(-50, 50), n=st.integers(2, 30))
def test_fit_plane_recovers_linear_surface(kp, kd, n):
    E, DE = np.meshgrid(np.linspace(-2, 2, n), np.linspace(-0.5, 3, n), indexing="ij")
    got = fit_plane(E, DE, kp * E + kd * DE)
    assert got == pytest.approx((kp, kd), abs=1e-9 * (1 + abs(kp) + abs(kd)))
    d, d_max = plane_residual(E, DE, kp * E + kd * DE, *got)
    assert d_max <= 1e-8 * (1 + abs(kp) + abs(kd))


def test_fit_on_even_geometry_linear_region():
    d1e, d1de, d1u = 0.03, 0.12, 0.56
    axis = make_axis(d1e, d1de, d1u, geometry="even")
    E, DE, U = control_surface(axis, 3 * d1e, 3 * d1de, n=31)
    assert E.shape == DE.shape == U.shape == (31, 31)
    assert E[0, 0] == -3 * d1e and DE[0, -1] == 3 * d1de
    kp, kd = fit_plane(E, DE, U)
    assert kp == pytest.approx(d1u / (2 * d1e), rel=1e-10)
    assert kd == pytest.approx(d1u / (2 * d1de), rel=1e-10)
    assert plane_residual(E, DE, U, kp, kd)[1] < 1e-10 * d1u


def test_plane_residual_is_eq_17():
    E, DE = np.meshgrid(np.linspace(-1, 1, 5), np.linspace(-1, 1, 3), indexing="ij")
    U = 2.0 * E - 1.0 * DE + 0.3 * E  # steeper in e than the plane (2, -1)
    d, d_max = plane_residual(E, DE, U, 2.0, -1.0)
    assert np.allclose(d, 0.3 * np.abs(E))  # (0.3 e) sgn(e) = 0.3 |e| >= 0
    assert d_max == pytest.approx(0.3)
    assert np.all(d[E == 0.0] == 0.0)


def test_paper_surface_saturates_beyond_fit_range():
    """Fitted over 3x the term range, the gains drop (saturation), and d changes sign."""
    axis = make_axis(math.radians(1.8), math.radians(7.0), 0.56)
    c3 = (1 + PAPER_RATIOS[1] + PAPER_RATIOS[2]) * math.radians(1.8)
    c3d = (1 + PAPER_RATIOS[1] + PAPER_RATIOS[2]) * math.radians(7.0)
    kp1, kd1 = fit_plane(*control_surface(axis, c3, c3d))
    kp3, kd3 = fit_plane(*control_surface(axis, 3 * c3, 3 * c3d))
    assert kp1 > kp3 > 0 and kd1 > kd3 > 0
    E, DE, U = control_surface(axis, 3 * c3, 3 * c3d)
    assert np.max(np.abs(U)) == pytest.approx(3 * 0.56, rel=1e-12)
