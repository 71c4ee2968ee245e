"""The stages after the attitude reference are one implementation for the built-in strategies and
the plug-in path: control_update is the position stage followed by attitude_to_motors, and
attitude_to_motors is the attitude law, the body torques and the allocation, bit for bit."""

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.control.allocation import euler_torque_to_body
from rig_emulator.control.controller import (CS_SIZE, OUT_SIZE, REF_SIZE, actuate, attitude_stage, attitude_to_motors,
                                             control_update, position_stage)
from rig_emulator.simulation.params import control_params


def _state(rng):
    pos, vel = rng.normal(0, 0.5, 3), rng.normal(0, 0.3, 3)
    att = rng.normal(0, 0.1, 9)  # phi, theta, psi, their rates, body rates
    ref = np.zeros(REF_SIZE)
    ref[1:11] = rng.normal(0, 0.5, 10)  # position, velocity, acceleration, yaw references
    ref[20] = np.nan  # no offboard thrust
    cstate = np.zeros(CS_SIZE)
    cstate[12:16] = rng.uniform(4.0, 7.0, 4)  # last thrusts (the SMC's gyroscopic term)
    return pos, vel, att, ref, cstate


@pytest.mark.parametrize("strategy", ["smc-flc", "flc", "smc", "pid"])
def test_control_update_is_the_position_stage_then_the_shared_tail(strategy):
    cp = control_params(load_config(scenario="helix", overrides={"control.strategy": strategy}))
    rng = np.random.default_rng()
    dt = 0.002
    for _ in range(3):
        pos, vel, att, ref, cstate = _state(rng)
        a = (cstate.copy(), np.zeros(OUT_SIZE), np.zeros(4), *(np.zeros(3) for _ in range(5)))
        control_update(dt, pos, vel, *att, ref, cp, *a)

        b = (cstate.copy(), np.zeros(OUT_SIZE), np.zeros(4), *(np.zeros(3) for _ in range(5)))
        c = (cstate.copy(), np.zeros(OUT_SIZE), np.zeros(4), *(np.zeros(3) for _ in range(5)))
        for cs, cout, v_cmd, e3, de3, acc3, s3, tau3 in (b, c):
            staged = position_stage(dt, pos, vel, *att[:3], ref, cp, cs, cout)
            u1, refs, flags = staged[0], staged[1:10], staged[10]
            if cout is b[1]:  # the shared tail
                attitude_to_motors(dt, *att, u1, *refs, flags, cp, cs, cout, v_cmd, e3, de3, acc3, s3, tau3)
            else:  # the same, stage by stage
                r0, dr0, a0, r1, dr1, a1, r2, dr2, a2 = refs
                attitude_stage(dt, *att, *refs, cp, cs, e3, de3, acc3, s3, tau3)
                u2, u3, u4 = euler_torque_to_body(tau3[0], tau3[1], tau3[2])
                actuate(u1, u2, u3, u4, flags, r0, r1, r2, dr0, dr1, dr2, s3, cp, cs, cout, v_cmd)
        for x, y, z in zip(a, b, c):
            assert np.array_equal(x, y, equal_nan=True) and np.array_equal(y, z, equal_nan=True)
        assert np.all(np.isfinite(a[2])) and np.any(a[2] > 0.0)  # it commanded the motors
