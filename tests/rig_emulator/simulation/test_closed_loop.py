"""Closed-loop runs of the scenarios: tracking, switching, determinism, bad config."""

import functools
import math

import numpy as np
import pytest

from protocol.mean_error import PAPER_TABLE_6
from rig_emulator.api import simulate as _simulate
from rig_emulator.config.loader import ConfigError

# these tests pin the ideal plant's behaviour (the default airframe is now the hardware rig)
simulate = functools.partial(_simulate, airframe="hilms-ideal")


@pytest.mark.parametrize("strategy", ["smc-flc", "flc"])
def test_helix_tracks_in_centimetres(strategy):
    """Eq. 46 with both of the paper's strategies: X, Y mean errors of Table 6's order."""
    me = simulate("helix", strategy=strategy, seed=1).mean_errors()
    paper = PAPER_TABLE_6[strategy]
    for axis in ("x_m", "y_m"):
        assert me[axis] < 5 * paper[axis], (axis, me[axis])
    assert me["z_m"] < 0.5
    assert all(math.isfinite(v) for v in me.values())


@pytest.mark.parametrize("strategy", ["smc-flc", "flc", "smc", "pid"])
def test_rectangle_flies_all_corners_with_8cm_switching(strategy):
    r = simulate("rectangle", strategy=strategy)
    reached = r.reached_t
    assert np.all(np.isfinite(reached)) and np.all(np.diff(reached) > 0)
    wp = np.array(r.config["guidance.waypoints"])
    pos, t = r.series["pos"], r.series["t"]
    for k, tk in enumerate(reached):
        i = np.searchsorted(t, tk)
        assert np.linalg.norm(pos[i] - wp[k]) < 0.08 + 0.05  # within the radius (+ one log period of motion)


@pytest.mark.parametrize("strategy", ["smc-flc", "flc", "smc", "pid"])
def test_harmonic_attitude_tracking(strategy):
    me = simulate("harmonic", strategy=strategy).mean_errors()
    assert me["phi_deg"] < 1.0 and me["theta_deg"] < 1.0


@pytest.mark.parametrize("strategy", ["smc-flc", "flc", "smc", "pid"])
def test_hover_shocks_recover(strategy):
    r = simulate("hover-shocks", strategy=strategy)
    euler, t = r.series["euler"], r.series["t"]
    peak = np.degrees(np.abs(euler[(t > 15) & (t < 16)])).max()
    final = np.degrees(np.abs(euler[t > 19.5])).max()
    assert peak > 0.5  # the shock on arm 4 at t = 15 s is visible
    assert final < peak  # and is being recovered


def test_same_seed_same_config_bit_identical():
    a = simulate("helix", strategy="smc-flc", duration=20.0, seed=7)
    b = simulate("helix", strategy="smc-flc", duration=20.0, seed=7)
    assert np.array_equal(a.log, b.log, equal_nan=True)


def test_airframe_presets_fly():
    for airframe in ("os4", "draganflyer"):
        r = simulate("hover", strategy="pid", airframe=airframe, duration=10.0)
        assert abs(r.series["pos"][-1, 2] - 1.0) < 0.1


@pytest.mark.parametrize(
    "kwargs, key",
    [
        (dict(airframe__mass=-1.0), "airframe.mass"),
        (dict(guidance__omega=0.0), "guidance.omega"),
        (dict(strategy="lqr"), "control.strategy"),
    ],
)
def test_bad_config_names_the_key(kwargs, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        simulate("harmonic", **kwargs)
