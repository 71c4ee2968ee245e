"""The built-in ``pid`` strategy (rig_emulator/controllers/builtin/pid.py) re-written as a controller plug-in.

It replaces both loops and commands u1 and body torques; the rig's allocation does the rest.
Everything it needs comes through the plug-in interface: the onboard estimates, the guidance
reference and the rig's constants in ``obs``, its gains in ``params``, its memory (reference
filters, integrators) in ``state``. Flown on the same rig and seed it gives the built-in
strategy's results (tests/rig_emulator/controllers/test_pid_equivalence.py), in both call
paths: ``rig-emulator simulate --scenario helix --controller
rig_emulator.controllers.examples.pid:PID`` (compiled), add ``--set controller.call=python``
for the same kernel run as Python.
"""

import math

import numba

from rig_emulator.control import plugin_layout as L
from rig_emulator.control.controller import REF_ACC, REF_ATT, REF_ATT_ACC, REF_ATT_RATE, REF_POS, REF_VEL, REF_YAW
from rig_emulator.controllers import CompiledController

# params (flat): the gains of rig.toml's [pid], in this order
ATT_KP, ATT_KI, ATT_KD, POS_KP, POS_KI, POS_KD, LIMIT = 0, 3, 6, 9, 12, 15, 18
# state: reference filters (value, rate) x 3, attitude integrators, position integrators, then
# scratch: (value, rate, acceleration) of the attitude reference per angle, desired accelerations
S_FILT, S_AINT, S_PINT, S_R, S_A = 0, 6, 9, 12, 21


@numba.njit(cache=True)
def _wrap(a):
    a = a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))
    if a <= -math.pi:
        a += 2.0 * math.pi
    return a


@numba.njit(cache=True)
def _pid(e, de, ff, p, gains, integ, i, dt):
    """ff + kp e + ki int(e) + kd de, the integral clamped to +-limit."""
    v = integ[i] + e * dt
    if v > p[LIMIT]:
        v = p[LIMIT]
    elif v < -p[LIMIT]:
        v = -p[LIMIT]
    integ[i] = v
    return ff + p[gains + i] * e + p[gains + 3 + i] * v + p[gains + 6 + i] * de


@numba.njit(cache=True)
def _filter(target, s, i, w, dt, wrap):
    """Critically damped 2nd-order reference filter (control/reference_filter.py)."""
    err = target - s[2 * i]
    if wrap:
        err = _wrap(err)
    acc = w * w * err - 2.0 * w * s[2 * i + 1]
    s[2 * i + 1] += acc * dt
    r = s[2 * i] + s[2 * i + 1] * dt
    s[2 * i] = _wrap(r) if wrap else r
    return s[2 * i], s[2 * i + 1], acc


@numba.njit(cache=True)
def pid_kernel(t, obs, p, s, out):
    dt, m, g, tilt = obs[L.O_DT], obs[L.O_MASS], obs[L.O_G], obs[L.O_MAX_TILT]
    phi, theta, psi = obs[L.O_EULER], obs[L.O_EULER + 1], obs[L.O_EULER + 2]
    ref = L.O_REF
    r = s[S_R:S_R + 9]  # (value, rate, acceleration) of the attitude reference per Euler angle
    if obs[L.O_MODE] == 0.0:  # position references: PID on the acceleration, then Eq. 33 and 35
        a = s[S_A:S_A + 3]
        for i in range(3):
            e = obs[ref + REF_POS + i] - obs[L.O_POS + i]
            de = obs[ref + REF_VEL + i] - obs[L.O_VEL + i]
            a[i] = _pid(e, de, obs[ref + REF_ACC + i], p, POS_KP, s[S_PINT:S_PINT + 3], i, dt)
        c = max(math.cos(theta) * math.cos(phi), math.cos(tilt))
        u1 = max(m * (g + a[2]) / c, 0.0)
        ux = m * a[0] / u1 if u1 > 1e-6 else 0.0
        uy = m * a[1] / u1 if u1 > 1e-6 else 0.0
        h = math.sqrt(ux * ux + uy * uy)
        if h > math.sin(tilt):
            ux, uy = ux * (math.sin(tilt) / h), uy * (math.sin(tilt) / h)
        psi_d = obs[ref + REF_YAW]
        phi_d = math.asin(ux * math.sin(psi_d) - uy * math.cos(psi_d))
        theta_d = math.asin((ux * math.cos(psi_d) + uy * math.sin(psi_d)) / math.cos(phi_d))
        targets = (phi_d, theta_d, psi_d)
        for i in range(3):
            if obs[L.O_RESET] != 0.0:
                s[S_FILT + 2 * i] = targets[i]
            r[3 * i], r[3 * i + 1], r[3 * i + 2] = _filter(targets[i], s, i, obs[L.O_REF_OMEGA], dt, i == 2)
    else:  # attitude references straight from guidance, u1 = m g
        u1 = m * g
        for i in range(3):
            r[3 * i] = obs[ref + REF_ATT + i]
            r[3 * i + 1] = obs[ref + REF_ATT_RATE + i]
            r[3 * i + 2] = obs[ref + REF_ATT_ACC + i]
    out[L.C_CMD] = u1
    for i in range(3):
        e = _wrap(r[6] - psi) if i == 2 else r[3 * i] - obs[L.O_EULER + i]
        de = r[3 * i + 1] - obs[L.O_EULER_RATE + i]
        tau = obs[L.O_IXX + i] * _pid(e, de, r[3 * i + 2], p, ATT_KP, s[S_AINT:S_AINT + 3], i, dt)
        out[L.C_CMD + 1 + i] = tau if i == 0 else -tau  # Euler-frame torque -> body FRD
        out[L.C_ATT_DES + i] = r[3 * i]
        out[L.C_ATT_RATE_DES + i] = r[3 * i + 1]
    return 0


class PID(CompiledController):
    """Cascaded PID on both loops (the built-in ``pid`` strategy), torques out."""

    replaces = "both"
    commands = "torques"
    kernel = pid_kernel
    state_size = 24
    param_prefix = "XPID_"
    params = {
        "att_kp": [100.0, 100.0, 16.0], "att_ki": [20.0, 20.0, 2.0], "att_kd": [20.0, 20.0, 8.0],
        "pos_kp": [2.0, 2.0, 4.0], "pos_ki": [0.2, 0.2, 0.8], "pos_kd": [2.5, 2.5, 4.0],
        "i_limit": 2.0,  # served as XPID_I_LIMIT (a MAVLink name has at most 16 characters)
    }
