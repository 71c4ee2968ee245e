"""Eq. 45 mean errors."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from protocol.mean_error import format_table, mean_error, mean_errors


def test_eq45_on_a_known_series():
    assert mean_error([1.0, 2.0, 3.0], [1.5, 2.0, 1.0]) == (0.5 + 0.0 + 2.0) / 3


def test_angles_wrap():
    assert math.isclose(mean_error([math.pi - 0.01], [-math.pi + 0.01], angle=True), 0.02, rel_tol=1e-9)


def test_nan_samples_are_left_out_and_all_nan_is_nan():
    assert mean_error([1.0, np.nan, 3.0], [0.0, 0.0, 3.0]) == 0.5
    assert math.isnan(mean_error([np.nan], [1.0]))


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=1, max_size=50))
def test_mean_error_is_mean_absolute_difference(values):
    a = np.array(values)
    assert math.isclose(mean_error(a, np.zeros_like(a)), float(np.mean(np.abs(a))), rel_tol=1e-12, abs_tol=1e-15)


def test_window_and_table():
    t = np.arange(10.0)
    euler = np.zeros((10, 3))
    euler_des = np.zeros((10, 3))
    euler_des[5:, 0] = math.radians(2.0)
    pos = np.zeros((10, 3))
    out = mean_errors(t, euler, euler_des, pos, pos, window=(5.0, 9.0))
    assert math.isclose(out["phi_deg"], 2.0) and out["x_m"] == 0.0
    text = format_table({"smc-flc": out})
    assert "ME_phi(deg)" in text and "2.0000" in text
