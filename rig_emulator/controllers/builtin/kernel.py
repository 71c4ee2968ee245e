"""The built-in strategies as a compiled controller on the plug-in interface.

The loop calls every controller the same way (:func:`rig_emulator.control.plugin_step.plugin_control`):
a function ``kernel(t, obs, params, state, out) -> int`` on float64 arrays laid out as
:mod:`rig_emulator.control.plugin_layout` says, reached through a function pointer. The four
built-in strategies (``control.strategy``: ``smc-flc``, ``flc``, ``smc``, ``pid``) are one such
kernel, :func:`strategy_kernel`, declared as a plug-in replacing both loops and commanding
``torques`` would be: it reads the onboard estimates, the guidance reference and the rig's
constants from ``obs``, its laws and gains from ``params`` (:func:`pack_params`, the rig's
``[smc]``, ``[flc]`` and ``[pid]`` sections and which law runs which loop) and keeps its memory
in ``state``; it returns u1 and the body torques, the attitude it aims at, its sliding surfaces,
uX, uY and its flags in ``out``. The rig's allocation (A6 inverse) and Eq. 40 inverse do the rest,
exactly as for a plug-in.

It is two functions, :func:`position_laws` (position law -> Eq. 35 -> reference filter) and
:func:`attitude_laws` (attitude law -> Euler-frame to body torques), which run the stages of
:mod:`rig_emulator.control.controller` with the same numbers in the same order as the stages
called directly with the rig's ControlParams (the logs are bit for bit the same). A plug-in that
replaces one loop gets the other from these two functions: the laws are compiled once.

``state`` keeps the layout of the stages' memory (``CS_FILTER`` .. ``CS_STARTED`` of
:mod:`rig_emulator.control.controller`), then the reference and scratch the stages write. The
built-in binding asks the loop not to zero it at a re-arm (``PluginParams.fresh`` False): the
integrators and filter rates carry over a re-arm, the filter values restart on the target
(:func:`rig_emulator.control.controller.shape_attitude`), as the rig's firmware does.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import carray, cfunc, types
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array
from numba.core.types.function_type import WrapperAddressProtocol

from rig_emulator._jit import jit
from rig_emulator.control import plugin_layout as L
from rig_emulator.control.allocation import euler_torque_to_body
from rig_emulator.control.controller import (
    CS_STARTED,
    CS_THRUST,
    OUT_SIZE as COUT_SIZE,
    OUT_UXY,
    REF_ACC_FF,
    REF_SIZE,
    REF_THRUST,
    attitude_stage,
    position_stage,
    shape_attitude,
)
from rig_emulator.controllers.builtin.fuzzy import RULE_TABLE, FuzzyAxis

#: What the stages read of ``cp`` (ControlParams), rebuilt inside the kernel from ``obs`` (the rig's
#: constants) and ``params`` (the laws' gains); the stages take either (they read fields by name).
LawParams = namedtuple(
    "LawParams",
    "pos_law att_law mass g ixx iyy izz rotor_inertia kf max_tilt ref_omega smc_k smc_lam smc_boundary smc_phi "
    "smcp_k smcp_lam smcp_phi flc_phi flc_theta flc_psi flc_x flc_y flc_z rule_table flc_rate_share "
    "pida_kp pida_ki pida_kd pidp_kp pidp_ki pidp_kd pid_limit",
)

# params (flat)
P_POS_LAW, P_ATT_LAW, P_ROTOR_INERTIA = 0, 1, 2
P_SMC_K, P_SMC_LAM, P_SMC_BOUNDARY, P_SMC_PHI = 3, 6, 9, 10
P_SMCP_K, P_SMCP_LAM, P_SMCP_PHI, P_FLC_RATE_SHARE = 11, 14, 17, 18
P_PIDA_KP, P_PIDA_KI, P_PIDA_KD, P_PIDP_KP, P_PIDP_KI, P_PIDP_KD, P_PID_LIMIT = 19, 22, 25, 28, 31, 34, 37
# six fuzzy axes (phi, theta, psi, x, y, z): their e terms (6 x 7 x 4), de terms (6 x 7 x 4), output centres (6 x 13)
N_TERMS, TERM_SIZE, N_CENTERS = 7, 4, 13
P_FLC_E = 38
P_FLC_DE = P_FLC_E + 6 * N_TERMS * TERM_SIZE
P_FLC_CENTERS = P_FLC_DE + 6 * N_TERMS * TERM_SIZE
N_PARAMS = P_FLC_CENTERS + 6 * N_CENTERS
_AXES = ("flc_phi", "flc_theta", "flc_psi", "flc_x", "flc_y", "flc_z")

# state
S_REF = CS_STARTED + 1  # REF_SIZE: the guidance reference the stages read (obs's, with the offboard entries)
S_COUT = S_REF + REF_SIZE  # the stages' record (they write uX, uY there)
S_SCRATCH = S_COUT + COUT_SIZE  # 5 x 3: e, de, acceleration, sliding surfaces, Euler-frame torques
S_TARGET = S_SCRATCH + 15  # 10: u1, then (value, rate, acceleration) of the shaped attitude reference per angle
STATE_SIZE = S_TARGET + 10


def pack_params(cp, out: np.ndarray | None = None) -> np.ndarray:
    """The kernel's ``params`` from a ControlParams (``out``: rewrite that array in place, the
    running rig's, after a parameter change)."""
    p = np.zeros(N_PARAMS) if out is None else out
    p[P_POS_LAW] = cp.pos_law
    p[P_ATT_LAW] = cp.att_law
    p[P_ROTOR_INERTIA] = cp.rotor_inertia
    p[P_SMC_K:P_SMC_K + 3] = cp.smc_k
    p[P_SMC_LAM:P_SMC_LAM + 3] = cp.smc_lam
    p[P_SMC_BOUNDARY] = 1.0 if cp.smc_boundary else 0.0
    p[P_SMC_PHI] = cp.smc_phi
    p[P_SMCP_K:P_SMCP_K + 3] = cp.smcp_k
    p[P_SMCP_LAM:P_SMCP_LAM + 3] = cp.smcp_lam
    p[P_SMCP_PHI] = cp.smcp_phi
    p[P_FLC_RATE_SHARE] = cp.flc_rate_share
    for base, name in ((P_PIDA_KP, "pida_kp"), (P_PIDA_KI, "pida_ki"), (P_PIDA_KD, "pida_kd"),
                       (P_PIDP_KP, "pidp_kp"), (P_PIDP_KI, "pidp_ki"), (P_PIDP_KD, "pidp_kd")):
        p[base:base + 3] = getattr(cp, name)
    p[P_PID_LIMIT] = cp.pid_limit
    for i, name in enumerate(_AXES):
        axis = getattr(cp, name)
        if axis.e_terms.shape != (N_TERMS, TERM_SIZE) or axis.de_terms.shape != (N_TERMS, TERM_SIZE) \
                or axis.out_centers.shape != (N_CENTERS,):
            raise ValueError(f"{name}: the built-in kernel takes {N_TERMS} input terms and {N_CENTERS} output terms")
        n = N_TERMS * TERM_SIZE
        p[P_FLC_E + i * n:P_FLC_E + (i + 1) * n] = axis.e_terms.ravel()
        p[P_FLC_DE + i * n:P_FLC_DE + (i + 1) * n] = axis.de_terms.ravel()
        p[P_FLC_CENTERS + i * N_CENTERS:P_FLC_CENTERS + (i + 1) * N_CENTERS] = axis.out_centers
    if not np.array_equal(cp.rule_table, RULE_TABLE):
        raise ValueError("the built-in kernel flies Table 1's rules")
    return p


def _view_of(dims: tuple):
    """An intrinsic ``view(arr, index)``: a C-contiguous view of the float64 array ``arr`` from
    ``arr[index]`` on, of the shape ``dims``. It is how the fuzzy law's term tables (2-D per axis)
    are read from the flat ``params`` at every update: no copy, and none of ``reshape``'s out-of-line
    shape checks. The view borrows ``arr``'s memory."""
    out = types.Array(types.float64, len(dims), "C")
    strides = tuple(8 * int(np.prod(dims[i + 1:])) for i in range(len(dims)))

    def view(typingctx, arr, index):
        def codegen(context, builder, sig, args):
            src = context.make_array(sig.args[0])(context, builder, args[0])
            result = context.make_array(out)(context, builder)
            intp = context.get_value_type(types.intp)
            populate_array(result, data=builder.gep(src.data, [args[1]]), shape=[intp(d) for d in dims],
                           strides=[intp(x) for x in strides], itemsize=intp(8), meminfo=None)
            return result._getvalue()

        return out(arr, index), codegen

    view.__name__ = f"view_{'x'.join(map(str, dims))}"
    return intrinsic(view)


_terms_view = _view_of((6, N_TERMS, TERM_SIZE))
_centers_view = _view_of((6, N_CENTERS))


@jit(inline="always")
def _law_params(obs, p):
    e = _terms_view(p, P_FLC_E)
    de = _terms_view(p, P_FLC_DE)
    c = _centers_view(p, P_FLC_CENTERS)
    return LawParams(
        np.int64(p[P_POS_LAW]), np.int64(p[P_ATT_LAW]), obs[L.O_MASS], obs[L.O_G], obs[L.O_IXX], obs[L.O_IYY],
        obs[L.O_IZZ], p[P_ROTOR_INERTIA], obs[L.O_KF], obs[L.O_MAX_TILT], obs[L.O_REF_OMEGA],
        p[P_SMC_K:P_SMC_K + 3], p[P_SMC_LAM:P_SMC_LAM + 3], p[P_SMC_BOUNDARY] != 0.0, p[P_SMC_PHI],
        p[P_SMCP_K:P_SMCP_K + 3], p[P_SMCP_LAM:P_SMCP_LAM + 3], p[P_SMCP_PHI],
        FuzzyAxis(e[0], de[0], c[0]), FuzzyAxis(e[1], de[1], c[1]), FuzzyAxis(e[2], de[2], c[2]),
        FuzzyAxis(e[3], de[3], c[3]), FuzzyAxis(e[4], de[4], c[4]), FuzzyAxis(e[5], de[5], c[5]), RULE_TABLE,
        p[P_FLC_RATE_SHARE],
        p[P_PIDA_KP:P_PIDA_KP + 3], p[P_PIDA_KI:P_PIDA_KI + 3], p[P_PIDA_KD:P_PIDA_KD + 3],
        p[P_PIDP_KP:P_PIDP_KP + 3], p[P_PIDP_KI:P_PIDP_KI + 3], p[P_PIDP_KD:P_PIDP_KD + 3], p[P_PID_LIMIT],
    )


@jit(inline="always")
def _inputs(obs, s):
    """The reference, the last thrust commands and the reset flag from ``obs`` into the stages' memory."""
    ref = s[S_REF:S_REF + REF_SIZE]
    for i in range(L.O_REF_SIZE):
        ref[i] = obs[L.O_REF + i]
    ref[REF_THRUST] = obs[L.O_REF_THRUST]
    ref[REF_ACC_FF] = obs[L.O_REF_ACC_FF]
    for i in range(4):
        s[CS_THRUST + i] = obs[L.O_THRUST_CMD + i]
    s[CS_STARTED] = 0.0 if obs[L.O_RESET] != 0.0 else 1.0
    return ref


@jit(nrt=False)
def position_laws(obs, p, s, out, shape_only):
    """The built-in strategy's position loop on the plug-in arrays: the position law (Eq. 37 FLC,
    sliding-mode or PID; in attitude guidance the guidance's references, u1 = m g) and Eq. 35, then
    the reference filter. ``shape_only``: the reference filter alone, on the attitude a position
    controller commanded in ``out[C_CMD + 1:C_CMD + 4]`` (u1 in ``out[C_CMD]``).

    Writes u1, the attitude reference, uX, uY and the flags into ``out``, the shaped reference (u1,
    then value, rate and acceleration per Euler angle) into ``s[S_TARGET:S_TARGET + 10]``. With
    :func:`attitude_laws` the one place the rig's laws are compiled: the built-in kernel runs both,
    the loop runs one of them for a plug-in that replaces the other."""
    lp = _law_params(obs, p)
    ref = _inputs(obs, s)
    cout = s[S_COUT:S_COUT + COUT_SIZE]
    dt = obs[L.O_DT]
    if shape_only:
        u1 = out[L.C_CMD]
        r0, dr0, a0, r1, dr1, a1, r2, dr2, a2 = shape_attitude(dt, out[L.C_CMD + 1], out[L.C_CMD + 2],
                                                               out[L.C_CMD + 3], lp.ref_omega, s)
        cout[OUT_UXY] = math.nan
        cout[OUT_UXY + 1] = math.nan
        flags = 0
    else:
        u1, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, flags = position_stage(
            dt, obs[L.O_POS:L.O_POS + 3], obs[L.O_VEL:L.O_VEL + 3], obs[L.O_EULER], obs[L.O_EULER + 1],
            obs[L.O_EULER + 2], ref, lp, s, cout)
    target = s[S_TARGET:S_TARGET + 10]
    target[0] = u1
    target[1] = r0
    target[2] = dr0
    target[3] = a0
    target[4] = r1
    target[5] = dr1
    target[6] = a1
    target[7] = r2
    target[8] = dr2
    target[9] = a2
    out[L.C_CMD] = u1
    out[L.C_ATT_DES] = r0
    out[L.C_ATT_DES + 1] = r1
    out[L.C_ATT_DES + 2] = r2
    out[L.C_ATT_RATE_DES] = dr0
    out[L.C_ATT_RATE_DES + 1] = dr1
    out[L.C_ATT_RATE_DES + 2] = dr2
    out[L.C_UXY] = cout[OUT_UXY]
    out[L.C_UXY + 1] = cout[OUT_UXY + 1]
    out[L.C_FLAGS] = flags


@jit(nrt=False)
def attitude_laws(obs, p, s, out):
    """The built-in strategy's attitude loop on the plug-in arrays: the attitude law (Eq. 5-13 SMC, FLC
    or PID) on the shaped reference in ``s[S_TARGET:]`` (:func:`position_laws`), its Euler-frame torques
    to body torques into ``out[C_CMD + 1:C_CMD + 4]``, its sliding surfaces into ``out[C_SURFACE:]``."""
    lp = _law_params(obs, p)
    t = s[S_TARGET:S_TARGET + 10]
    e3 = s[S_SCRATCH:S_SCRATCH + 3]
    de3 = s[S_SCRATCH + 3:S_SCRATCH + 6]
    acc3 = s[S_SCRATCH + 6:S_SCRATCH + 9]
    s3 = s[S_SCRATCH + 9:S_SCRATCH + 12]
    tau3 = s[S_SCRATCH + 12:S_SCRATCH + 15]
    attitude_stage(obs[L.O_DT], obs[L.O_EULER], obs[L.O_EULER + 1], obs[L.O_EULER + 2], obs[L.O_EULER_RATE],
                   obs[L.O_EULER_RATE + 1], obs[L.O_EULER_RATE + 2], obs[L.O_BODY_RATE], obs[L.O_BODY_RATE + 1],
                   obs[L.O_BODY_RATE + 2], t[1], t[2], t[3], t[4], t[5], t[6], t[7], t[8], t[9], lp, s,
                   e3, de3, acc3, s3, tau3)
    u2, u3, u4 = euler_torque_to_body(tau3[0], tau3[1], tau3[2])
    out[L.C_CMD + 1] = u2
    out[L.C_CMD + 2] = u3
    out[L.C_CMD + 3] = u4
    for i in range(3):
        out[L.C_SURFACE + i] = s3[i]


@jit(inline="always")  # compiled into its C wrapper (strategy_cfunc), the only caller in a run
def strategy_kernel(t, obs, p, s, out):
    """One update of the built-in strategy ``params`` names (Fig. 7): position law (Eq. 37 FLC,
    sliding-mode or PID) -> Eq. 35 -> reference filter -> attitude law (Eq. 5-13 SMC, FLC or PID)
    -> body torques. Returns 0."""
    position_laws(obs, p, s, out, np.bool_(False))  # np.bool_: a literal would compile a specialisation per value
    attitude_laws(obs, p, s, out)
    return 0


def _strategy_call(t, o, p, s, out):
    return strategy_kernel(t, carray(o, (L.OBS_SIZE,), np.float64), carray(p, (N_PARAMS,), np.float64),
                           carray(s, (STATE_SIZE,), np.float64), carray(out, (L.OUT_SIZE,), np.float64))


_CFUNC = None


def strategy_cfunc():
    """:func:`strategy_kernel` behind the plug-in signature (a C function the loop calls through its
    pointer, as it calls a compiled plug-in); compiled, or loaded from the cache, on first use."""
    global _CFUNC
    if _CFUNC is None:
        _CFUNC = cfunc(STRATEGY_POINTER.signature(), cache=True, nopython=True)(_strategy_call)
    return _CFUNC


class StrategyPointer(WrapperAddressProtocol):
    """The loop's function pointer to :func:`strategy_cfunc`, compiled when its address is first
    needed: numba types the loop from :meth:`signature` alone, so a cold start compiles the loop
    first, with the laws the kernel calls in the helper process (rig_emulator/compile_helper.py),
    and then only the kernel's small C wrapper."""

    def __wrapper_address__(self):
        return strategy_cfunc().address

    _sig = None

    def signature(self):
        sig = self._sig
        if sig is None:  # (plugin_step imports this module: the signature is looked up on first use)
            from rig_emulator.control.plugin_step import PLUGIN_SIG

            sig = StrategyPointer._sig = PLUGIN_SIG
        return sig

    def compile_now(self) -> None:
        """Compile (or load) the kernel now (the split compile calls this while its helper runs)."""
        strategy_cfunc()


STRATEGY_POINTER = StrategyPointer()
