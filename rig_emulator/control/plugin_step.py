"""A controller plug-in's turn in the step loop (docs/how-to/your-controller.md).

The loop calls :func:`plugin_control` instead of
:func:`~rig_emulator.control.controller.control_update` when a plug-in is loaded. It fills
the observation array (:mod:`rig_emulator.control.plugin_layout`), calls the plug-in
through a function pointer of the one signature :data:`PLUGIN_SIG` and applies its
command through the rig's own stages (position law, reference filter, attitude law,
allocation) that the plug-in does not replace.

The pointer is numba's first-class function type: a compiled plug-in is a ``cfunc`` (a
call costs nanoseconds), a Python plug-in a ctypes callback into the interpreter (about a
microsecond plus its own work). Either way the loop is compiled once, for the type, not
per plug-in.
"""

import math
from collections import namedtuple

from numba import types

from rig_emulator._jit import jit
from rig_emulator.control.controller import (
    record_decision,
    CS_STARTED,
    CS_THRUST,
    MODE_POSITION,
    OUT_THRUST_CMD,
    OUT_UXY,
    REF_MODE,
    REF_THRUST,
    actuate,
    attitude_to_motors,
    position_stage,
    shape_attitude,
)
from rig_emulator.control.plugin_layout import (
    C_ATT_DES,
    C_ATT_RATE_DES,
    C_CMD,
    ERR_NONFINITE,
    ERR_RETURNED,
    K_ATTITUDE,
    K_THRUSTS,
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
    O_REF_THRUST,
    O_REF_SIZE,
    O_RESET,
    O_T,
    O_THRUST,
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
from rig_emulator.physics.motors import thrust_from_voltage, voltage_for_thrust

#: ``status = update(t, obs*, params*, state*, out*)``: float64 time, four float64 buffers.
PLUGIN_SIG = types.int64(types.float64, types.voidptr, types.voidptr, types.voidptr, types.voidptr)

#: What the loop gets about the plug-in (the function pointer travels as its own argument).
#: ``mode`` P_*, ``kind`` K_*, ``div`` physics steps per plug-in call, ``raw`` copy raw
#: samples into obs; ``obs``/``params``/``state``/``out`` float64 arrays, ``status`` int64 (S_*).
PluginParams = namedtuple("PluginParams", "mode kind div raw obs params state out status")


@jit(nrt=False)
def plugin_control(k, t, dt, ctrl_dt, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz,
                   ref, pp, cp, cstate, cout, v_cmd, scratch, x, sp, ss, pl, fn):
    """One control update (``ctrl_dt``: the rig's control period) with the plug-in ``fn``; False when the plug-in failed (the
    loop disarms; ``pl.status`` says why and when)."""
    first = cstate[CS_STARTED] == 0.0
    obs = pl.obs
    out = pl.out
    s3 = scratch[3]
    tau3 = scratch[4]
    flags = 0
    r0 = dr0 = a0 = r1 = dr1 = a1 = r2 = dr2 = a2 = math.nan
    u1 = math.nan
    if pl.mode == P_POSITION:
        # the rig's attitude loop runs at the control rate; the plug-in every pl.div steps
        if ref[REF_MODE] != MODE_POSITION:
            u1, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, flags = position_stage(ctrl_dt, pos, vel, phi, theta, psi, ref, cp,
                                                                              cstate, cout)
        else:
            if first or k % pl.div == 0:
                if not _call(k, t, dt * pl.div, first, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz,
                             ref, pp, x, sp, ss, pl, fn):
                    return False
            u1 = out[C_CMD]
            r0, dr0, a0, r1, dr1, a1, r2, dr2, a2 = shape_attitude(ctrl_dt, out[C_CMD + 1], out[C_CMD + 2],
                                                                   out[C_CMD + 3], cp, cstate)
            cout[OUT_UXY] = math.nan
            cout[OUT_UXY + 1] = math.nan
            cstate[CS_STARTED] = 1.0
        attitude_to_motors(ctrl_dt, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, u1, r0, dr0, a0, r1, dr1, a1,
                           r2, dr2, a2, flags, cp, cstate, cout, v_cmd, scratch[0], scratch[1], scratch[2], s3, tau3)
        return True

    if pl.mode == P_ATTITUDE:
        u1, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, flags = position_stage(ctrl_dt, pos, vel, phi, theta, psi, ref, cp,
                                                                          cstate, cout)
        obs[O_ATT_TARGET] = r0
        obs[O_ATT_TARGET + 1] = r1
        obs[O_ATT_TARGET + 2] = r2
        obs[O_ATT_RATE_TARGET] = dr0
        obs[O_ATT_RATE_TARGET + 1] = dr1
        obs[O_ATT_RATE_TARGET + 2] = dr2
        obs[O_ATT_ACC_TARGET] = a0
        obs[O_ATT_ACC_TARGET + 1] = a1
        obs[O_ATT_ACC_TARGET + 2] = a2
        obs[O_THRUST_TARGET] = u1
    if not _call(k, t, ctrl_dt, first, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz,
                 ref, pp, x, sp, ss, pl, fn):
        return False
    cstate[CS_STARTED] = 1.0
    if pl.mode == P_BOTH:
        r0 = out[C_ATT_DES]
        r1 = out[C_ATT_DES + 1]
        r2 = out[C_ATT_DES + 2]
        dr0 = out[C_ATT_RATE_DES]
        dr1 = out[C_ATT_RATE_DES + 1]
        dr2 = out[C_ATT_RATE_DES + 2]
        cout[OUT_UXY] = math.nan
        cout[OUT_UXY + 1] = math.nan
    for i in range(3):
        s3[i] = math.nan  # no sliding surfaces: the plug-in's law is its own
    if pl.kind == K_TORQUES:
        actuate(out[C_CMD], out[C_CMD + 1], out[C_CMD + 2], out[C_CMD + 3], flags, r0, r1, r2, dr0, dr1, dr2, s3,
                cp, cstate, cout, v_cmd)
        return True
    # per-motor commands: the motor driver clips to its supply (Eq. 40 inverse)
    forces = cout[OUT_THRUST_CMD : OUT_THRUST_CMD + 4]
    for i in range(4):
        c = out[C_CMD + i]
        if pl.kind == K_VOLTAGES:
            v = min(max(c, 0.0), cp.v_max)
        else:
            v = voltage_for_thrust(c, cp.k_v, cp.v_max)
        v_cmd[i] = v
        forces[i] = thrust_from_voltage(v, cp.k_v, cp.f_max)
        cstate[CS_THRUST + i] = forces[i]
    record_decision(forces, flags, r0, r1, r2, dr0, dr1, dr2, s3, cp, cout)  # s3 is NaN here
    return True


@jit(nrt=False)
def _call(k, t, period, first, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, ref, pp, x, sp, ss, pl, fn):
    """Fill ``pl.obs``, call the plug-in, check its answer; False (and ``pl.status``) on failure."""
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
        if sp.simulate:
            obs[O_THRUST + i] = ss.thrust_est[i]
        else:
            obs[O_THRUST + i] = pp.thrust_efficiency[i] * thrust_from_voltage(x[13 + i], pp.k_v, pp.f_ceiling)
    for i in range(O_REF_SIZE):  # ref grew past 20 (offboard entries): never into O_ATT_TARGET
        obs[O_REF + i] = ref[i]
    obs[O_REF_THRUST] = ref[REF_THRUST]  # the offboard thrust set-point, in a slot of its own past the 20 reference values
    if not sp.estimated:
        obs[O_TRUE_VALID] = 1.0
        for i in range(13):
            obs[O_TRUE + i] = x[i]
    if pl.raw and sp.simulate:
        raw = ss.imu_raw
        for m in range(raw.shape[0]):
            for j in range(9):
                obs[O_IMU_RAW + 9 * m + j] = raw[m, j]
        for i in range(4):
            obs[O_CELL_RAW + i] = ss.cell_raw[i]
    if first:
        for i in range(pl.state.shape[0]):
            pl.state[i] = 0.0
    out = pl.out
    for i in range(OUT_SIZE):
        out[i] = math.nan
    rc = fn(t, obs.ctypes, pl.params.ctypes, pl.state.ctypes, out.ctypes)
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
