"""The controller's turn in the step loop (docs/how-to/your-controller.md).

The loop calls :func:`plugin_control` for every controller: the built-in strategy
(:mod:`rig_emulator.controllers.builtin.kernel`), a compiled plug-in or a Python one. It fills
the observation array (:mod:`rig_emulator.control.plugin_layout`), calls the controller
through a function pointer of the one signature :data:`PLUGIN_SIG` and applies its
command through the rig's own stages (position law, reference filter, attitude law,
allocation) that the controller does not replace.

The pointer is numba's first-class function type: a compiled controller is a ``cfunc`` (a
call costs nanoseconds), a Python plug-in a cffi or ctypes callback into the interpreter
(about a microsecond plus its own work). Either way the loop is compiled once, for the type,
not per controller.
"""

import math
from collections import namedtuple

import numpy as np
from numba import types

from rig_emulator._jit import jit
from rig_emulator.control.controller import (
    CS_STARTED,
    CS_THRUST,
    MODE_POSITION,
    OUT_THRUST_CMD,
    OUT_UXY,
    REF_ACC_FF,
    REF_MODE,
    REF_THRUST,
    actuate,
    record_decision,
)
from rig_emulator.control.plugin_layout import (
    C_ATT_DES,
    C_ATT_RATE_DES,
    C_CMD,
    C_FLAGS,
    C_SURFACE,
    C_UXY,
    ERR_NONFINITE,
    ERR_RETURNED,
    K_TORQUES,
    K_VOLTAGES,
    O_ATT_ACC_TARGET,
    O_ATT_RATE_TARGET,
    O_ATT_TARGET,
    O_BODY_RATE,
    O_CELL_RAW,
    O_DT,
    O_EULER,
    O_EULER_RATE,
    O_IMU_RAW,
    O_MODE,
    O_POS,
    O_REF,
    O_REF_ACC_FF,
    O_REF_THRUST,
    O_REF_SIZE,
    O_RESET,
    O_T,
    O_THRUST,
    O_THRUST_CMD,
    O_THRUST_TARGET,
    O_TRUE,
    O_TRUE_VALID,
    O_VEL,
    OUT_SIZE,
    P_ATTITUDE,
    P_BOTH,
    P_POSITION,
    S_CODE,
    S_RETURN,
    S_STEP,
)
from rig_emulator.controllers.builtin.kernel import S_TARGET, attitude_laws, position_laws
from rig_emulator.physics.motors import thrust_from_voltage, voltage_for_thrust

#: ``status = update(t, obs*, params*, state*, out*)``: float64 time, four float64 buffers.
PLUGIN_SIG = types.int64(types.float64, types.voidptr, types.voidptr, types.voidptr, types.voidptr)

#: What the loop gets about the controller (the function pointer travels as its own argument).
#: ``mode`` P_*, ``kind`` K_*, ``div`` physics steps per call, ``raw`` copy raw samples into
#: obs, ``fresh`` zero ``state`` on the first call after arming (a plug-in's contract; the built-in
#: laws keep their integrators over a re-arm, as the rig's firmware does);
#: ``obs``/``params``/``state``/``out`` float64 arrays, ``status`` int64 (S_*).
#: ``laws``/``rig_state``/``rig_out``: the built-in strategy's parameters (``kernel.pack_params``), memory
#: and output, for the loop the plug-in does not replace.
PluginParams = namedtuple("PluginParams", "mode kind div raw fresh obs params state out status laws rig_state rig_out")


@jit(inline="always")
def plugin_control(k, t, dt, ctrl_dt, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz,
                   ref, pp, cp, cstate, cout, v_cmd, scratch, x, sp, ss, pl, fn):
    """One control update (``ctrl_dt``: the rig's control period) with the controller ``fn``; False when it
    failed (the loop disarms; ``pl.status`` says why and when).

    Inlined into the loop, it calls the update out of line with only what it needs: a call passes a
    namedtuple of arrays field by field, and the rig's parameters and sensing state are hundreds of
    fields. A plug-in that replaces one loop gets the built-in strategy's stages for the other
    (:mod:`rig_emulator.controllers.builtin.kernel`'s ``position_laws``, ``attitude_laws``, on ``pl.laws``, its memory in
    ``pl.rig_state``)."""
    return _control(k, t, dt, ctrl_dt, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, ref, cstate, cout,
                    v_cmd, scratch[3], x, sp.simulate, sp.estimated, ss.thrust_est, ss.imu_raw, ss.cell_raw,
                    pp.thrust_efficiency, pp.k_v, pp.f_ceiling,
                    Actuators(cp.arm_length, cp.km_over_kf, cp.f_max, cp.alloc_priority, cp.k_v, cp.v_max), pl, fn)


@jit(nrt=False)
def _control(k, t, dt, ctrl_dt, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, ref, cstate, cout, v_cmd, s3,
             x, simulate, estimated, thrust_est, imu_raw, cell_raw, thrust_efficiency, k_v, f_ceiling, act, pl, fn):
    """:func:`plugin_control` out of line, on what it needs."""
    first = cstate[CS_STARTED] == 0.0
    obs = pl.obs
    _observe(t, ctrl_dt, first, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, ref, cstate, x, simulate,
             estimated, thrust_est, imu_raw, cell_raw, thrust_efficiency, k_v, f_ceiling, pl)
    cmd = pl.out  # the command applied: the controller's, or the rig's attitude loop's under a position plug-in
    flags = 0
    if pl.mode == P_POSITION:
        cmd = pl.rig_out
        if ref[REF_MODE] != MODE_POSITION:  # attitude guidance: the built-in strategy flies it
            position_laws(obs, pl.laws, pl.rig_state, cmd, np.bool_(False))
        else:  # the plug-in every pl.div steps, the rig's reference filter and attitude loop at the control rate
            if first or k % pl.div == 0:
                obs[O_DT] = dt * pl.div
                if not _invoke(k, t, first, pl, fn):
                    return False
                obs[O_DT] = ctrl_dt
            for i in range(4):
                cmd[C_CMD + i] = pl.out[C_CMD + i]
            position_laws(obs, pl.laws, pl.rig_state, cmd, np.bool_(True))
        attitude_laws(obs, pl.laws, pl.rig_state, cmd)
        cout[OUT_UXY] = cmd[C_UXY]
        cout[OUT_UXY + 1] = cmd[C_UXY + 1]
    else:
        if pl.mode == P_ATTITUDE:  # the built-in position loop hands the plug-in its attitude target
            rig = pl.rig_out
            position_laws(obs, pl.laws, pl.rig_state, rig, np.bool_(False))
            target = pl.rig_state[S_TARGET:S_TARGET + 10]
            obs[O_THRUST_TARGET] = target[0]
            for i in range(3):
                obs[O_ATT_TARGET + i] = target[1 + 3 * i]
                obs[O_ATT_RATE_TARGET + i] = target[2 + 3 * i]
                obs[O_ATT_ACC_TARGET + i] = target[3 + 3 * i]
            cout[OUT_UXY] = rig[C_UXY]
            cout[OUT_UXY + 1] = rig[C_UXY + 1]
            flags = int(rig[C_FLAGS])
        if not _invoke(k, t, first, pl, fn):
            return False
        if pl.mode == P_BOTH:
            cout[OUT_UXY] = cmd[C_UXY]
            cout[OUT_UXY + 1] = cmd[C_UXY + 1]
        else:  # the attitude reference recorded is the rig's position loop's
            for i in range(3):
                cmd[C_ATT_DES + i] = obs[O_ATT_TARGET + i]
                cmd[C_ATT_RATE_DES + i] = obs[O_ATT_RATE_TARGET + i]
    cstate[CS_STARTED] = 1.0
    _apply(cmd, flags, pl.mode == P_POSITION or pl.kind == K_TORQUES, pl.kind == K_VOLTAGES, act, cstate, cout, v_cmd,
           s3)
    return True


#: what applying a command needs of ControlParams (a call passes a namedtuple field by field: not all of it)
Actuators = namedtuple("Actuators", "arm_length km_over_kf f_max alloc_priority k_v v_max")


@jit(inline="always")
def _apply(cmd, flags, torques, voltages, act, cstate, cout, v_cmd, s3):
    """The command in ``cmd`` to the motors: u1 and body torques through the allocation (A6 inverse),
    or per-motor voltages (clipped to the supply) or thrusts (Eq. 40 inverse); recorded in ``cout``."""
    for i in range(3):
        s3[i] = cmd[C_SURFACE + i]  # NaN unless the controller reports sliding surfaces
    if not math.isnan(cmd[C_FLAGS]):
        flags |= int(cmd[C_FLAGS])
    r0 = cmd[C_ATT_DES]
    r1 = cmd[C_ATT_DES + 1]
    r2 = cmd[C_ATT_DES + 2]
    dr0 = cmd[C_ATT_RATE_DES]
    dr1 = cmd[C_ATT_RATE_DES + 1]
    dr2 = cmd[C_ATT_RATE_DES + 2]
    if torques:
        actuate(cmd[C_CMD], cmd[C_CMD + 1], cmd[C_CMD + 2], cmd[C_CMD + 3], flags, r0, r1, r2, dr0, dr1, dr2, s3,
                act, cstate, cout, v_cmd)
        return
    forces = cout[OUT_THRUST_CMD : OUT_THRUST_CMD + 4]
    for i in range(4):
        c = cmd[C_CMD + i]
        if voltages:
            v = min(max(c, 0.0), act.v_max)
        else:
            v = voltage_for_thrust(c, act.k_v, act.v_max)
        v_cmd[i] = v
        forces[i] = thrust_from_voltage(v, act.k_v, act.f_max)
        cstate[CS_THRUST + i] = forces[i]
    record_decision(forces, flags, r0, r1, r2, dr0, dr1, dr2, s3, act, cout)


@jit(nrt=False)
def _observe(t, period, first, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, ref, cstate, x, simulate,
             estimated, thrust_est, imu_raw, cell_raw, thrust_efficiency, k_v, f_ceiling, pl):
    """Fill ``pl.obs`` for this control step. The thrusts it observes are the filtered load cells
    (``thrust_est``) with the sensor models on, else the motors' (Eq. 40 of the state's voltages,
    ``thrust_efficiency`` for motor faults)."""
    obs = pl.obs
    obs[O_T] = t
    obs[O_DT] = period
    obs[O_RESET] = 1.0 if first else 0.0
    obs[O_MODE] = ref[REF_MODE]
    obs[O_EULER] = phi
    obs[O_EULER + 1] = theta
    obs[O_EULER + 2] = psi
    obs[O_EULER_RATE] = dphi
    obs[O_EULER_RATE + 1] = dtheta
    obs[O_EULER_RATE + 2] = dpsi
    obs[O_BODY_RATE] = wx
    obs[O_BODY_RATE + 1] = wy
    obs[O_BODY_RATE + 2] = wz
    for i in range(3):
        obs[O_POS + i] = pos[i]
        obs[O_VEL + i] = vel[i]
    for i in range(4):
        if simulate:
            obs[O_THRUST + i] = thrust_est[i]
        else:
            obs[O_THRUST + i] = thrust_efficiency[i] * thrust_from_voltage(x[13 + i], k_v, f_ceiling)
    for i in range(O_REF_SIZE):  # ref grew past 20 (offboard entries): never into O_ATT_TARGET
        obs[O_REF + i] = ref[i]
    obs[O_REF_THRUST] = ref[REF_THRUST]  # the offboard thrust set-point, in a slot of its own past the 20 reference values
    obs[O_REF_ACC_FF] = ref[REF_ACC_FF]
    for i in range(4):
        obs[O_THRUST_CMD + i] = cstate[CS_THRUST + i]
    if not estimated:
        obs[O_TRUE_VALID] = 1.0
        for i in range(13):
            obs[O_TRUE + i] = x[i]
    if pl.raw and simulate:
        for m in range(imu_raw.shape[0]):
            for j in range(9):
                obs[O_IMU_RAW + 9 * m + j] = imu_raw[m, j]
        for i in range(4):
            obs[O_CELL_RAW + i] = cell_raw[i]


@jit(nrt=False)
def _invoke(k, t, first, pl, fn):
    """Call the controller on ``pl.obs`` and check its answer; False (and ``pl.status``) on failure."""
    if first and pl.fresh:
        for i in range(pl.state.shape[0]):
            pl.state[i] = 0.0
    out = pl.out
    for i in range(OUT_SIZE):
        out[i] = math.nan
    rc = fn(t, pl.obs.ctypes, pl.params.ctypes, pl.state.ctypes, out.ctypes)
    if rc != 0:
        pl.status[S_CODE] = ERR_RETURNED
    else:
        for i in range(4):
            if not math.isfinite(out[C_CMD + i]):
                pl.status[S_CODE] = ERR_NONFINITE
    if pl.status[S_CODE] != 0:
        pl.status[S_STEP] = k
        pl.status[S_RETURN] = rc
        return False
    return True
