"""The built-in strategies' kernel is the rig's stages behind the plug-in interface: from the same
numbers in ``obs`` it decides, bit for bit, what the position stage and the attitude stage decide
when called directly with the rig's ControlParams."""

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.control import plugin_layout as L
from rig_emulator.control.allocation import euler_torque_to_body
from rig_emulator.control.controller import (CS_SIZE, CS_STARTED, OUT_SIZE, OUT_UXY, REF_SIZE, attitude_stage,
                                             position_stage)
from rig_emulator.controllers.builtin.kernel import STATE_SIZE, pack_params, strategy_kernel
from rig_emulator.controllers.runtime import fill_rig_constants
from rig_emulator.simulation.params import control_params


def _state(rng, attitude_mode=False):
    pos, vel = rng.normal(0, 0.5, 3), rng.normal(0, 0.3, 3)
    att = rng.normal(0, 0.1, 9)  # phi, theta, psi, their rates, body rates
    ref = np.zeros(REF_SIZE)
    ref[0] = 1.0 if attitude_mode else 0.0
    ref[1:20] = rng.normal(0, 0.5, 19)  # position, velocity, acceleration, yaw, attitude references
    ref[20] = np.nan  # no offboard thrust
    cstate = np.zeros(CS_SIZE)
    cstate[0:12] = rng.normal(0, 0.2, 12)  # filters and integrators carried over
    cstate[12:16] = rng.uniform(4.0, 7.0, 4)  # last thrusts (the SMC's gyroscopic term)
    cstate[CS_STARTED] = rng.integers(0, 2)
    return pos, vel, att, ref, cstate


def _obs(cp, dt, pos, vel, att, ref, cstate):
    obs = np.full(L.OBS_SIZE, np.nan)
    fill_rig_constants(obs, cp)
    obs[L.O_DT] = dt
    obs[L.O_RESET] = 1.0 if cstate[CS_STARTED] == 0.0 else 0.0
    obs[L.O_MODE] = ref[0]
    obs[L.O_EULER:L.O_EULER + 9] = att
    obs[L.O_POS:L.O_POS + 3] = pos
    obs[L.O_VEL:L.O_VEL + 3] = vel
    obs[L.O_REF:L.O_REF + L.O_REF_SIZE] = ref[:L.O_REF_SIZE]
    obs[L.O_REF_THRUST] = ref[20]
    obs[L.O_REF_ACC_FF] = ref[21]
    obs[L.O_THRUST_CMD:L.O_THRUST_CMD + 4] = cstate[12:16]
    return obs


@pytest.mark.parametrize("attitude_mode", [False, True])
@pytest.mark.parametrize("strategy", ["smc-flc", "flc", "smc", "pid"])
def test_the_builtin_kernel_is_the_rig_stages_bit_for_bit(strategy, attitude_mode):
    cp = control_params(load_config(scenario="helix", overrides={"control.strategy": strategy}))
    params = pack_params(cp)
    rng = np.random.default_rng()
    dt = 0.002
    for _ in range(5):
        pos, vel, att, ref, cstate = _state(rng, attitude_mode)
        state = np.zeros(STATE_SIZE)
        state[:12] = cstate[:12]
        out = np.full(L.OUT_SIZE, np.nan)
        assert strategy_kernel(0.0, _obs(cp, dt, pos, vel, att, ref, cstate), params, state, out) == 0

        cs, cout, e3, de3, acc3, s3, tau3 = cstate.copy(), np.zeros(OUT_SIZE), *(np.zeros(3) for _ in range(5))
        u1, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, flags = position_stage(dt, pos, vel, *att[:3], ref, cp, cs, cout)
        attitude_stage(dt, *att, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, cp, cs, e3, de3, acc3, s3, tau3)
        u = (u1, *euler_torque_to_body(tau3[0], tau3[1], tau3[2]))
        assert np.array_equal(out[L.C_CMD:L.C_CMD + 4], u)
        assert np.array_equal(out[L.C_ATT_DES:L.C_ATT_DES + 3], [r0, r1, r2])
        assert np.array_equal(out[L.C_ATT_RATE_DES:L.C_ATT_RATE_DES + 3], [dr0, dr1, dr2])
        assert np.array_equal(out[L.C_SURFACE:L.C_SURFACE + 3], s3)
        assert np.array_equal(out[L.C_UXY:L.C_UXY + 2], cout[OUT_UXY:OUT_UXY + 2])
        assert out[L.C_FLAGS] == flags
        assert np.array_equal(state[:12], cs[:12])  # the same memory: filters and integrators
        assert np.all(np.isfinite(u)) and u[0] > 0.0


def test_a_parameter_change_repacks_the_kernel_params_in_place():
    cp = control_params(load_config(scenario="helix"))
    p = pack_params(cp)
    cp2 = control_params(load_config(scenario="helix", overrides={"control.strategy": "pid", "pid.attitude_kp": [1, 2, 3]}))
    q = pack_params(cp2, out=p)
    assert q is p and np.array_equal(p, pack_params(cp2)) and not np.array_equal(p, pack_params(cp))
