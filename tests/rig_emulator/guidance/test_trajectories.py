"""Eq. 46 exactly as published, Eq. 44, and derivatives consistent with the positions."""

import math

import numpy as np
import pytest

from rig_emulator.guidance.trajectories import harmonic_attitude, helix_eq46


def _helix(t):
    p, v, a = np.zeros(3), np.zeros(3), np.zeros(3)
    helix_eq46(t, p, v, a)
    return p, v, a


@pytest.mark.parametrize(
    "t, expected",
    [
        (0.0, (0, 0, 0)),
        (2.99, (0, 0, 0)),
        (5.0, (0.6, 0.6, 0.6)),
        (11.999, (0.3 * 8.999, 0.3 * 8.999, 0.3 * 8.999)),
        (12.0, (2.5, 2.5, 2.7)),
        (20.0, (2.5 * math.cos(2.4), 2.5 * math.sin(2.4) + 2.5, 5.1)),
        (30.0, (2.5 * math.cos(5.4), 2.5 * math.sin(5.4) + 2.5, 8.0)),
        (55.0, (2.5 * math.cos(12.9), 2.5 * math.sin(12.9) + 2.5, 8.0)),
    ],
)
def test_eq46_values(t, expected):
    assert np.allclose(_helix(t)[0], expected, atol=1e-12)


def test_published_jump_at_t12_is_kept():
    before, after = _helix(12.0 - 1e-9)[0], _helix(12.0)[0]
    assert np.allclose(before[:2], [2.7, 2.7], atol=1e-6) and np.allclose(after[:2], [2.5, 2.5])


@pytest.mark.parametrize("t", [4.0, 8.5, 13.0, 25.0, 40.0])
def test_eq46_derivatives(t):
    h = 1e-6
    p0, v0, a0 = _helix(t - h)
    p1, v1, a1 = _helix(t + h)
    _, v, a = _helix(t)
    assert np.allclose((p1 - p0) / (2 * h), v, atol=1e-6)
    assert np.allclose((v1 - v0) / (2 * h), a, atol=1e-5)


def test_eq44_harmonic():
    amp = np.radians([10.0, 10.0, 0.0])
    att, rate, acc = np.zeros(3), np.zeros(3), np.zeros(3)
    harmonic_attitude(2.0, amp, 0.4, att, rate, acc)
    assert att[0] == pytest.approx(math.radians(10.0) * math.sin(0.8))
    assert rate[1] == pytest.approx(math.radians(10.0) * 0.4 * math.cos(0.8))
    assert acc[0] == pytest.approx(-math.radians(10.0) * 0.16 * math.sin(0.8))
    assert att[2] == 0.0
