"""The collective thrust that hovers (SET_ATTITUDE_TARGET.thrust; MPC_THR_HOVER): flown on the default
plant, the hardware rig, whose thrust chain needs more than m g / u1_max."""

import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.headless.hover_thrust import (HoverThrustEstimate, fly_fractions, fly_thrust, hover_fraction,
                                                settle, _rig)
from rig_emulator.simulation.live import LiveRig


def test_the_learnt_hover_fraction_holds_the_altitude_where_m_g_over_u1_max_sinks():
    rig = _rig("hilms", 0, {})
    estimate = HoverThrustEstimate()
    psi = settle(rig, 20.0, estimate)  # 20 s hold at 2 m in position mode: the estimate learns
    served = estimate.value(rig)
    nominal = rig.hover_thrust_fraction()
    assert estimate.learnt_s > 10.0
    assert 0.80 < served < 0.83 and nominal == pytest.approx(0.7808, abs=1e-4)
    held = fly_thrust(rig, psi, served, 5.0)  # level attitude set-points at that thrust
    assert held.duration_s == pytest.approx(5.0) and abs(held.climb_m) < 0.7  # (measured +0.48 m)
    sank = fly_fractions("hilms", [nominal], settle_s=20.0, window_s=5.0)[0]
    assert sank.climb_m < -1.5  # at m g / u1_max the hardware rig comes down


def test_the_thrust_chain_of_the_ideal_plant_hovers_at_m_g_over_u1_max():
    """On the ideal plant (here because its motors follow Eq. 40 exactly) the thrust chain's steady
    solution is m g / u1_max; on the hardware rig it is above it (bias, convex curve, gains)."""
    ideal = LiveRig(load_config("hilms-ideal"))
    assert hover_fraction(ideal) == pytest.approx(ideal.hover_thrust_fraction(), abs=1e-9)
    hw = LiveRig(load_config("hilms"))
    assert hover_fraction(hw) > hw.hover_thrust_fraction() + 0.02
    assert HoverThrustEstimate().value(hw) == hover_fraction(hw)  # before any flight


def test_the_hover_thrust_command_flies_given_thrusts(capsys):
    import json

    from rig_emulator.cli import main

    assert main(["hover-thrust", "--airframe", "hilms-ideal", "--thrust", "0.6", "--settle", "4", "--window", "1",
                 "--json"]) == 0
    (out,) = json.loads(capsys.readouterr().out)
    (trial,) = out["trials"]
    assert out["airframe"] == "hilms-ideal" and trial["fraction"] == 0.6 and trial["climb_m"] < -0.5
