"""The compiled step loop: guidance -> control -> actuators -> physics, one physics step at a time.

``run_steps`` advances the rig by ``n_steps`` physics steps starting at step ``k_start``
(time = k dt exactly, no accumulated rounding). Control runs every ``ctrl_div`` steps with
a zero-order hold on the motor commands; a log row is written every ``log_div`` steps.
It can be called repeatedly on the same arrays: a headless run calls it once, the MAVLink
rig calls it in chunks between link services.
"""

from rig_emulator._jit import jit
from rig_emulator.control.controller import (
    OUT_ATT_DES,
    OUT_ATT_RATE_DES,
    OUT_FLAGS,
    OUT_S,
    OUT_U,
    OUT_UXY,
    CS_STARTED,
    REF_MODE,
    REF_POS,
    REF_VEL,
    control_update,
)
from rig_emulator.guidance.runner import GS_INDEX, guidance_update
from rig_emulator.physics.integrator import rk4_step
from rig_emulator.physics.motors import thrust_from_voltage
from rig_emulator.physics.rotation import euler_from_quat, euler_rates_from_body_rates
from rig_emulator.simulation import log_layout as L


@jit
def run_steps(
    k_start, n_steps, dt, ctrl_div, log_div,
    x, v_cmd, pp, cp, gp, wind, gusts, shocks, extra,
    cstate, gstate, reached_t, ref, cout, scratch, work, R, log, log_row, armed,
):
    """Advance the rig; returns the next free log row.

    Disarmed, the motors are commanded to 0 V and the controller is reset so that it
    starts afresh on arming.
    """
    ctrl_dt = dt * ctrl_div
    for k in range(k_start, k_start + n_steps):
        t = k * dt
        if not armed:
            for i in range(4):
                v_cmd[i] = 0.0
            cstate[CS_STARTED] = 0.0
        elif k % ctrl_div == 0:
            phi, theta, psi = euler_from_quat(x[6], x[7], x[8], x[9])
            dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, x[10], x[11], x[12])
            guidance_update(t, x[0:3], gp, gstate, reached_t, ref)
            control_update(
                ctrl_dt, x[0:3], x[3:6], phi, theta, psi, dphi, dtheta, dpsi, x[10], x[11], x[12],
                ref, cp, cstate, cout, v_cmd, scratch[0], scratch[1], scratch[2], scratch[3], scratch[4],
            )
        if k % log_div == 0 and log_row < log.shape[0]:
            row = log[log_row]
            phi, theta, psi = euler_from_quat(x[6], x[7], x[8], x[9])
            dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, x[10], x[11], x[12])
            row[L.T] = t
            for i in range(3):
                row[L.POS + i] = x[i]
                row[L.VEL + i] = x[3 + i]
                row[L.OMEGA + i] = x[10 + i]
                row[L.POS_DES + i] = ref[REF_POS + i]
                row[L.VEL_DES + i] = ref[REF_VEL + i]
                row[L.EULER_DES + i] = cout[OUT_ATT_DES + i]
                row[L.EULER_RATE_DES + i] = cout[OUT_ATT_RATE_DES + i]
                row[L.S + i] = cout[OUT_S + i]
            row[L.EULER] = phi
            row[L.EULER + 1] = theta
            row[L.EULER + 2] = psi
            row[L.EULER_RATE] = dphi
            row[L.EULER_RATE + 1] = dtheta
            row[L.EULER_RATE + 2] = dpsi
            for i in range(4):
                row[L.THRUST + i] = thrust_from_voltage(x[13 + i], pp.k_v, pp.f_ceiling)
                row[L.V_CMD + i] = v_cmd[i]
                row[L.U + i] = cout[OUT_U + i]
            row[L.FLAGS] = cout[OUT_FLAGS]
            row[L.WAYPOINT] = gstate[GS_INDEX]
            row[L.MODE] = ref[REF_MODE]
            row[L.UXY] = cout[OUT_UXY]
            row[L.UXY + 1] = cout[OUT_UXY + 1]
            log_row += 1
        rk4_step(t, dt, x, v_cmd, pp, wind, gusts, shocks, extra, work, R)
    return log_row
