"""The load-cell thrust loop (a reading of Sec. 3-3, control/thrust_loop.py): sign, size, bound, faults."""

import math

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.control.controller import CS_SIZE, CS_THRUST_CORR, OUT_SIZE, OUT_THRUST_CMD
from rig_emulator.control.thrust_loop import thrust_loop
from rig_emulator.physics.motors import GRAM_FORCE_N
from rig_emulator.simulation.params import control_params

IDEAL = load_config("hilms-ideal")
DT = 0.002  # the 500 Hz control period


def _cp(tc, limit_grf=100.0):
    return control_params(IDEAL.with_overrides({"motors.thrust_loop_time_constant": tc,
                                                "motors.thrust_loop_limit_grf": limit_grf}))


def _run(cp, seconds, f_des, true_thrust, flagged=0, cstate=None):
    """Close the loop on a plant whose (measured) thrust is ``true_thrust(v)``; returns the
    measured thrust of each motor after ``seconds`` and the controller memory."""
    cstate = np.zeros(CS_SIZE) if cstate is None else cstate
    cout = np.zeros(OUT_SIZE)
    cout[OUT_THRUST_CMD:OUT_THRUST_CMD + 4] = f_des
    v = np.array([f / cp.k_v for f in f_des])  # actuate(): the Eq. 40 inverse
    meas = np.array([true_thrust(x) for x in v])
    for _ in range(int(round(seconds / DT))):
        v[:] = [f / cp.k_v for f in f_des]
        thrust_loop(DT, cp, cstate, cout, meas, flagged, v)
        meas[:] = [true_thrust(x) for x in v]
    return meas, cstate, v


def test_off_on_the_ideal_plant_on_the_hardware_rig():
    assert IDEAL["motors.thrust_loop_time_constant"] == 0.0
    assert control_params(IDEAL).thrust_loop_rate == 0.0
    hw = load_config("hilms")
    assert hw["motors.thrust_loop_time_constant"] == 200.0
    assert control_params(hw).thrust_loop_rate == pytest.approx(1.0 / 200.0)
    assert control_params(hw).thrust_loop_limit == pytest.approx(100.0 * GRAM_FORCE_N)


@pytest.mark.parametrize("tc", [5.0, 20.0])
def test_removes_a_known_thrust_bias_at_its_time_constant(tc):
    cp = _cp(tc)
    bias = -50.0 * GRAM_FORCE_N  # Eq. 40 overstating the running thrust by 50 gr.F
    f_des = [5.47, 5.47, 5.47, 5.47]

    def plant(v):
        return cp.k_v * v + bias

    meas, cs, v = _run(cp, tc, f_des, plant)
    # sign: the true thrust is short, so the command is raised; size: the error has decayed
    # as exp(-t / T) after one time constant (to the discretisation's (1 - dt/T)^n)
    corr = cs[CS_THRUST_CORR:CS_THRUST_CORR + 4]
    assert np.all(corr > 0.0)
    expected = (1.0 - DT / tc) ** round(tc / DT)
    assert expected == pytest.approx(math.exp(-1.0), rel=1e-3)
    np.testing.assert_allclose(np.asarray(f_des) - meas, -bias * expected, rtol=1e-9)
    np.testing.assert_allclose(v, (np.asarray(f_des) + corr) / cp.k_v, rtol=1e-12)
    meas, cs, _ = _run(cp, 4.0 * tc, f_des, plant, cstate=cs)  # five time constants in all
    assert np.max(np.abs(np.asarray(f_des) - meas)) < 0.01 * abs(bias)
    np.testing.assert_allclose(cs[CS_THRUST_CORR:CS_THRUST_CORR + 4], -bias, rtol=0.01)


def test_a_dead_cell_drives_its_correction_to_the_bound_and_no_further():
    cp = _cp(5.0, limit_grf=100.0)
    f_des = [5.47, 5.47, 5.47, 5.47]

    def plant(v):  # every cell reads 0: dead, but not (yet) flagged by the supervisor
        return 0.0

    _, cs, v = _run(cp, 60.0, f_des, plant)
    lim = 100.0 * GRAM_FORCE_N
    np.testing.assert_allclose(cs[CS_THRUST_CORR:CS_THRUST_CORR + 4], lim, rtol=0, atol=0)
    np.testing.assert_allclose(v, (5.47 + lim) / cp.k_v, rtol=1e-12)


def test_a_flagged_cell_freezes_its_correction_and_a_motor_commanded_off_stays_off():
    cp = _cp(5.0)
    cs = np.zeros(CS_SIZE)
    cs[CS_THRUST_CORR:CS_THRUST_CORR + 4] = [0.1, 0.2, 0.3, 0.4]
    f_des = [5.0, 5.0, 0.0, 5.0]

    def plant(v):
        return 0.0

    _, cs, v = _run(cp, 1.0, f_des, plant, flagged=0b0010, cstate=cs)  # cell 2 flagged
    corr = cs[CS_THRUST_CORR:CS_THRUST_CORR + 4]
    assert corr[1] == 0.2 and corr[2] == 0.3  # frozen (flagged) and held (motor 3 off)
    assert corr[0] > 0.1 and corr[3] > 0.4
    assert v[2] == 0.0
    assert v[1] == pytest.approx((5.0 + 0.2) / cp.k_v)


def test_closed_on_the_hardware_rig_the_collective_thrust_error_goes():
    """On ``hilms`` (Eq. 40 overstating the running thrust by 50 gr.F) the commanded u1 exceeds the
    load cells' sum by about the bias when open; with the loop it matches them in the mean."""
    from rig_emulator.api import simulate
    from rig_emulator.simulation import log_layout as L

    gaps = []
    for tc in (0.0, 5.0):
        log = simulate("hover", "flc", duration=40.0, seed=0, overrides={"motors.thrust_loop_time_constant": tc}).log
        late = log[:, L.T] >= 30.0
        meas = log[late, L.THRUST_MEAS:L.THRUST_MEAS + 4].sum(axis=1)
        gaps.append(float(np.mean(log[late, L.U] - meas)))
    assert gaps[0] > 1.0  # open: about 4 x 50 gr.F = 1.96 N less the convex curve's part
    assert abs(gaps[1]) < 0.05


def test_identify_fits_the_time_constant_only_outside_the_refused_hole():
    from gcs_tools.identify.params import make_param
    from rig_emulator.config.loader import ConfigError

    p = make_param("motors.thrust_loop_time_constant", 20.0, 1000.0)
    assert (p.lo, p.hi) == (20.0, 1000.0)
    with pytest.raises(ConfigError, match="refused interval"):
        make_param("motors.thrust_loop_time_constant", 0.0, 200.0)
