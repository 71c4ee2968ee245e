"""Pure helpers of the reference benchmarks (flc-vs-skfuzzy, cf-vs-ahrs); never timings.

Nothing here imports scikit-fuzzy or ahrs: only our side's numpy helpers are tested.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import cf_vs_ahrs as cf
from benchmarks import flc_vs_skfuzzy as flc
from benchmarks.harness import REGISTRY
from rig_emulator.control.fuzzy import make_axis, membership
from rig_emulator.physics.rotation import rwb_from_euler


@pytest.mark.parametrize("geometry", ["paper", "even"])
def test_term_membership_matches_the_compiled_one(geometry):
    axis = make_axis(math.radians(1.8), math.radians(7.0), 0.05, geometry=geometry)
    for terms in (axis.e_terms, axis.de_terms):
        xs = np.linspace(-5 * terms[-1, 0], 5 * terms[-1, 0], 401)
        for i in range(terms.shape[0]):
            ours = flc.term_membership(xs, terms, i)
            ref = np.array([membership(float(x), terms, i) for x in xs])
            assert np.allclose(ours, ref, atol=1e-12, rtol=0)


def test_input_universe_holds_every_vertex_and_is_sorted():
    axis = make_axis(math.radians(1.8), math.radians(7.0), 0.05)
    for terms in (axis.e_terms, axis.de_terms):
        u = flc.input_universe(terms)
        assert np.all(np.diff(u) > 0)
        vertices = np.concatenate([terms[:, 0], terms[1:, 0] - terms[1:, 1], terms[:-1, 0] + terms[:-1, 2]])
        for v in vertices:
            assert np.min(np.abs(u - v)) == 0.0
        assert u[0] < terms[0, 0] and u[-1] > terms[-1, 0]
        # linear interpolation on the universe reproduces the memberships exactly
        xs = np.linspace(u[0], u[-1], 997)
        for i in range(terms.shape[0]):
            interp = np.interp(xs, u, flc.term_membership(u, terms, i))
            assert np.allclose(interp, flc.term_membership(xs, terms, i), atol=1e-12)


def test_output_sets_are_disjoint_symmetric_rectangles():
    centers = make_axis(1.0, 1.0, 0.05).out_centers
    u, mfs = flc.output_sets(centers)
    assert mfs.shape == (len(centers), len(u))
    assert np.all(np.diff(u) > 0)
    assert np.all(mfs.max(axis=1) == 1.0)
    assert np.all((mfs > 0).sum(axis=0) <= 1)  # no two sets overlap
    for k, y in enumerate(centers):
        support = u[mfs[k] > 0]
        assert math.isclose(0.5 * (support[0] + support[-1]), y, abs_tol=1e-15)
        # the centroid of the set (trapezoid rule on the universe) is its center
        area = np.trapezoid(mfs[k], u)
        assert math.isclose(np.trapezoid(mfs[k] * u, u) / area, y, abs_tol=1e-12)
    with pytest.raises(ValueError):
        flc.output_sets(centers, half_width_frac=0.6)


def test_grid_inputs_span_both_universes():
    axis = make_axis(math.radians(1.8), math.radians(7.0), 0.05)
    e, de = flc.grid_inputs(axis.e_terms, axis.de_terms, 4)
    assert e.shape == de.shape == (16,)
    eu, du = flc.input_universe(axis.e_terms), flc.input_universe(axis.de_terms)
    assert e.min() == eu[0] and e.max() == eu[-1] and de.min() == du[0] and de.max() == du[-1]


def test_rwb_many_matches_rwb_from_euler():
    rng = np.random.default_rng(0)
    a = rng.uniform(-3, 3, (50, 3))
    R = cf.rwb_many(a[:, 0], a[:, 1], a[:, 2])
    for k in range(50):
        assert np.allclose(R[k], rwb_from_euler(*a[k]), atol=1e-15)


def test_trajectory_is_consistent():
    m_w = np.array([1e-5, 2e-5, -4e-5])
    truth, omega, f, m = cf.trajectory(200, 1e-3, np.radians([25.0, 20.0, 40.0]), 0.8, 0.3, m_w)
    assert truth.shape == omega.shape == f.shape == m.shape == (200, 3)
    assert np.allclose(np.linalg.norm(f, axis=1), cf.GRAVITY)
    assert np.allclose(np.linalg.norm(m, axis=1), np.linalg.norm(m_w))
    k = 17
    R = rwb_from_euler(*truth[k])
    assert np.allclose(f[k], R.T @ np.array([0.0, 0.0, cf.GRAVITY]), atol=1e-12)
    assert np.allclose(m[k], R.T @ m_w, atol=1e-18)


def test_hold_every_and_rms_error():
    x = np.arange(12.0).reshape(6, 2)
    held = cf.hold_every(x, 3)
    assert np.array_equal(held, x[[0, 0, 0, 3, 3, 3]])
    truth = np.zeros((4, 3))
    est = np.array([[9.0, 9.0, 9.0]] + [[math.radians(1.0), -math.radians(2.0), 2 * math.pi]] * 3)
    assert np.allclose(cf.rms_error_deg(est, truth, 1), [1.0, 2.0, 0.0], atol=1e-9)
    assert cf.wrap_pi(math.pi + 0.1) == pytest.approx(-math.pi + 0.1)


def test_both_benchmarks_are_registered():
    assert REGISTRY.benchmarks["flc-vs-skfuzzy"].probes == (flc.SKFUZZY_PROBE, flc.FLC_PROBE)
    assert REGISTRY.benchmarks["cf-vs-ahrs"].probes == (cf.OURS_PROBE, cf.AHRS_PROBE)
