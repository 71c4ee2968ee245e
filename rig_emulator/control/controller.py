"""The stages of one control update: guidance references in, motor voltage commands out.

Flow (Fig. 7): position law -> (u1, uX, uY) -> Eq. 35 -> desired attitude -> reference
filter -> attitude law -> Euler-frame torques -> body torques -> allocation (A6 inverse)
-> motor voltages (Eq. 40 inverse). In attitude mode (the paper's attitude experiments)
the references come straight from guidance and u1 is the hover thrust m g.

The built-in strategies run :func:`position_stage` and :func:`attitude_stage` inside their
kernel on the plug-in interface (:mod:`rig_emulator.controllers.builtin.kernel`); the step loop
applies every controller's command through :func:`actuate` (:mod:`rig_emulator.control.plugin_step`),
and a plug-in that replaces one loop gets the rig's stage for the other.

Layouts:

* ``ref`` (from guidance, see guidance/runner.py): REF_* indices below. In position mode
  a NaN reference is "not controlled", as in PX4's trajectory set-points: a NaN position
  (per axis) zeroes that axis' position error (velocity control), a NaN velocity its
  velocity error, a NaN acceleration its feed-forward (:func:`_axis_errors`).
* ``cstate`` (controller memory): CS_* indices.
* ``cout`` (what the controller decided, for logs and telemetry): OUT_* indices.
"""

import math

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.control.allocation import allocate
from rig_emulator.controllers.builtin.fuzzy import flc_axis
from rig_emulator.controllers.builtin.pid import pid_axis
from rig_emulator.control.reference_filter import reference_step, wrap_angle
from rig_emulator.controllers.builtin.smc import smc_attitude, switch
from rig_emulator.controllers.builtin.strategies import FLC, SMC
from rig_emulator.control.thrust_direction import collective_thrust, desired_tilt
from rig_emulator.physics.motors import rotor_speed, voltage_for_thrust
from rig_emulator.physics.rotation import euler_rates_from_body_rates

# guidance output
REF_MODE = 0  # 0: position references, 1: attitude references
REF_POS = 1
REF_VEL = 4
REF_ACC = 7
REF_YAW = 10
REF_ATT = 11
REF_ATT_RATE = 14
REF_ATT_ACC = 17
# Offboard references (set-point messages, guidance/offboard.py; every other guidance leaves
# them at their "unused" values, so the paper's laws run exactly as before):
REF_THRUST = 20  # collective thrust u1 (N) in attitude and rate modes; NaN: hover thrust m g
REF_ACC_FF = 21  # 1: the FLC position law also takes REF_ACC as a feed-forward (Eq. 37 has none)
REF_SIZE = 22
MODE_POSITION = 0.0
MODE_ATTITUDE = 1.0
MODE_RATES = 2.0  # REF_ATT_RATE holds body rates (FRD, rad/s); the attitude angles are not controlled

# controller memory
CS_FILTER = 0  # 6: (value, rate) of the phi, theta, psi reference filters
CS_ATT_INT = 6  # 3: attitude PID integrators
CS_POS_INT = 9  # 3: position PID integrators
CS_THRUST = 12  # 4: last commanded thrusts (N), for the rotor gyroscopic estimate
CS_STARTED = 16  # 1: 0 until the first update has initialised the filters
# actuator test, not controller state: DO_MOTOR_TEST spins motors while disarmed (simulation/live.py motor_test)
CS_TEST_V = 17  # 4: voltage commanded to each motor during the test
CS_TEST_UNTIL = 21  # 1: the test ends at this time (s)
CS_THRUST_CORR = 22  # 4: the load-cell thrust loop's correction per motor (N; control/thrust_loop.py)
CS_SIZE = 26

# controller output
OUT_U = 0  # 4: u1 (N), u2, u3, u4 (N m, body axes, as allocated)
OUT_ATT_DES = 4  # 3: desired phi, theta, psi
OUT_ATT_RATE_DES = 7  # 3
OUT_S = 10  # 3: sliding surfaces s = e' + lambda e
OUT_FLAGS = 13  # allocation SATURATED_* | TILT_CLAMPED
OUT_THRUST_CMD = 14  # 4: commanded thrusts (N)
OUT_UXY = 18  # 2: virtual inputs uX, uY (Eq. 34)
OUT_SIZE = 20


@jit(inline="always")
def _axis_errors(ref, k, pos, vel):
    """(position error, velocity error, acceleration feed-forward) of world axis k; NaN
    references are not controlled (0). Finite references give exactly the paper's errors."""
    p = ref[REF_POS + k]
    v = ref[REF_VEL + k]
    a = ref[REF_ACC + k]
    e = 0.0 if math.isnan(p) else p - pos[k]
    de = 0.0 if math.isnan(v) else v - vel[k]
    return e, de, (0.0 if math.isnan(a) else a)


# The stages are inline="always": each is compiled into its caller, the built-in strategy's laws
# (controllers/builtin/kernel.py); a call passed cp (ControlParams) and the other arguments field by
# field at every control step.
@jit(inline="always")
def position_stage(dt, pos, vel, phi, theta, psi, ref, cp, cstate, cout):
    """Position law (or, in attitude mode, the guidance's attitude references and u1 = m g).

    Returns (u1, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, flags): the collective thrust and the
    shaped attitude references (value, rate, acceleration per Euler angle).
    """
    flags = 0
    if ref[REF_MODE] == MODE_POSITION:
        ex, dex, ffx = _axis_errors(ref, 0, pos, vel)
        ey, dey, ffy = _axis_errors(ref, 1, pos, vel)
        ez, dez, ffz = _axis_errors(ref, 2, pos, vel)
        weight = cp.mass * cp.g
        if cp.pos_law == FLC:
            if cp.flc_rate_share != 1.0:  # derivative on the measurement, partly or wholly
                # (dex + vel) is the desired velocity, 0 where an offboard set-point leaves it free (NaN).
                # Only the derivative of a position error is taken partly on the measurement: an axis
                # without a position reference (offboard velocity control) tracks v_des - v in full,
                # else it would settle at share x v_des (0.34 of a 0.5 m/s command)
                if not math.isnan(ref[REF_POS]):
                    dex = cp.flc_rate_share * (dex + vel[0]) - vel[0]
                if not math.isnan(ref[REF_POS + 1]):
                    dey = cp.flc_rate_share * (dey + vel[1]) - vel[1]
                if not math.isnan(ref[REF_POS + 2]):
                    dez = cp.flc_rate_share * (dez + vel[2]) - vel[2]
            # Eq. 37: uX, uY and the altitude correction of u1 from three fuzzy axes
            ux = flc_axis(ex, dex, cp.flc_x, cp.rule_table)
            uy = flc_axis(ey, dey, cp.flc_y, cp.rule_table)
            vertical = weight + flc_axis(ez, dez, cp.flc_z, cp.rule_table)
            if ref[REF_ACC_FF] != 0.0:  # offboard acceleration set-point: m a added to the thrust vector
                vertical += cp.mass * ffz
            u1 = collective_thrust(vertical, phi, theta, cp.max_tilt)
            if ref[REF_ACC_FF] != 0.0 and u1 > 1e-6:
                ux += cp.mass * ffx / u1
                uy += cp.mass * ffy / u1
        else:
            if cp.pos_law == SMC:
                ax = ffx + cp.smcp_lam[0] * dex + cp.smcp_k[0] * switch(dex + cp.smcp_lam[0] * ex, True, cp.smcp_phi)
                ay = ffy + cp.smcp_lam[1] * dey + cp.smcp_k[1] * switch(dey + cp.smcp_lam[1] * ey, True, cp.smcp_phi)
                az = ffz + cp.smcp_lam[2] * dez + cp.smcp_k[2] * switch(dez + cp.smcp_lam[2] * ez, True, cp.smcp_phi)
            else:
                integ = cstate[CS_POS_INT : CS_POS_INT + 3]
                ax = pid_axis(ex, dex, ffx, cp.pidp_kp[0], cp.pidp_ki[0], cp.pidp_kd[0], integ, np.int64(0), dt, cp.pid_limit)
                ay = pid_axis(ey, dey, ffy, cp.pidp_kp[1], cp.pidp_ki[1], cp.pidp_kd[1], integ, np.int64(1), dt, cp.pid_limit)
                az = pid_axis(ez, dez, ffz, cp.pidp_kp[2], cp.pidp_ki[2], cp.pidp_kd[2], integ, np.int64(2), dt, cp.pid_limit)
            u1 = collective_thrust(cp.mass * (cp.g + az), phi, theta, cp.max_tilt)
            if u1 > 1e-6:
                ux = cp.mass * ax / u1
                uy = cp.mass * ay / u1
            else:
                ux = 0.0
                uy = 0.0
        cout[OUT_UXY] = ux
        cout[OUT_UXY + 1] = uy
        psi_d = ref[REF_YAW]
        phi_d, theta_d, tilt_flags = desired_tilt(ux, uy, psi_d, cp.max_tilt)
        flags |= tilt_flags
        r0, dr0, a0, r1, dr1, a1, r2, dr2, a2 = shape_attitude(dt, phi_d, theta_d, psi_d, cp.ref_omega, cstate)
    else:
        # attitude and rate modes: u1 is the hover thrust unless an offboard set-point gives it
        u1 = cp.mass * cp.g if math.isnan(ref[REF_THRUST]) else ref[REF_THRUST]
        cout[OUT_UXY] = 0.0
        cout[OUT_UXY + 1] = 0.0
        if ref[REF_MODE] == MODE_RATES:
            # body-rate set-point: the angle references follow the attitude (no angle error) and
            # the rate references are the Euler-angle rates of the commanded body rates (Eq. 4)
            r0 = phi
            r1 = theta
            r2 = psi
            dr0, dr1, dr2 = euler_rates_from_body_rates(phi, theta, ref[REF_ATT_RATE], ref[REF_ATT_RATE + 1],
                                                        ref[REF_ATT_RATE + 2])
        else:
            r0 = ref[REF_ATT]
            r1 = ref[REF_ATT + 1]
            r2 = ref[REF_ATT + 2]
            dr0 = ref[REF_ATT_RATE]
            dr1 = ref[REF_ATT_RATE + 1]
            dr2 = ref[REF_ATT_RATE + 2]
        a0 = ref[REF_ATT_ACC]
        a1 = ref[REF_ATT_ACC + 1]
        a2 = ref[REF_ATT_ACC + 2]
    cstate[CS_STARTED] = 1.0
    return u1, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2, flags


@jit(nrt=False)  # a call (position_stage and a position plug-in's path both shape): compiled once
def shape_attitude(dt, phi_d, theta_d, psi_d, ref_omega, cstate):
    """The reference filters (control/reference_filter.py) on a desired attitude; started on
    the target at the first update after arming. Returns (r, dr, a) per Euler angle."""
    if cstate[CS_STARTED] == 0.0:
        cstate[CS_FILTER + 0] = phi_d
        cstate[CS_FILTER + 2] = theta_d
        cstate[CS_FILTER + 4] = psi_d
    # np.int64() / np.bool_(): literal constant arguments would compile one specialisation per value
    r0, dr0, a0 = reference_step(phi_d, cstate, np.int64(0), ref_omega, dt, np.bool_(False))
    r1, dr1, a1 = reference_step(theta_d, cstate, np.int64(1), ref_omega, dt, np.bool_(False))
    r2, dr2, a2 = reference_step(psi_d, cstate, np.int64(2), ref_omega, dt, np.bool_(True))
    return r0, dr0, a0, r1, dr1, a1, r2, dr2, a2


@jit(inline="always")
def attitude_stage(dt, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, r0, dr0, a0, r1, dr1, a1, r2, dr2, a2,
                   cp, cstate, e3, de3, acc3, s3, tau3):
    """Attitude law: Euler-frame torques into ``tau3``, sliding surfaces into ``s3``."""
    e3[0] = r0 - phi
    e3[1] = r1 - theta
    e3[2] = wrap_angle(r2 - psi)
    de3[0] = dr0 - dphi
    de3[1] = dr1 - dtheta
    de3[2] = dr2 - dpsi
    acc3[0] = a0
    acc3[1] = a1
    acc3[2] = a2

    if cp.att_law == SMC:
        omega_r = 0.0
        for i in range(4):
            w = rotor_speed(cstate[CS_THRUST + i], cp.kf)
            omega_r += w if (i % 2 == 0) else -w
        smc_attitude(e3, de3, acc3, phi, theta, dphi, dtheta, wx, wy, wz, omega_r, cp, s3, tau3)
    else:
        for i in range(3):
            s3[i] = de3[i] + cp.smc_lam[i] * e3[i]
        if cp.att_law == FLC:
            tau3[0] = flc_axis(e3[0], de3[0], cp.flc_phi, cp.rule_table)
            tau3[1] = flc_axis(e3[1], de3[1], cp.flc_theta, cp.rule_table)
            tau3[2] = flc_axis(e3[2], de3[2], cp.flc_psi, cp.rule_table)
        else:
            integ = cstate[CS_ATT_INT : CS_ATT_INT + 3]
            tau3[0] = cp.ixx * pid_axis(e3[0], de3[0], a0, cp.pida_kp[0], cp.pida_ki[0], cp.pida_kd[0], integ, np.int64(0), dt, cp.pid_limit)
            tau3[1] = cp.iyy * pid_axis(e3[1], de3[1], a1, cp.pida_kp[1], cp.pida_ki[1], cp.pida_kd[1], integ, np.int64(1), dt, cp.pid_limit)
            tau3[2] = cp.izz * pid_axis(e3[2], de3[2], a2, cp.pida_kp[2], cp.pida_ki[2], cp.pida_kd[2], integ, np.int64(2), dt, cp.pid_limit)


@jit(inline="always")
def actuate(u1, u2, u3, u4, flags, r0, r1, r2, dr0, dr1, dr2, s3, cp, cstate, cout, v_cmd):
    """Allocation (A6 inverse) of (u1 N, u2..u4 N m about the body axes) to motor thrusts and
    voltages; records what was decided in ``cout``. Returns the flags."""
    forces = cout[OUT_THRUST_CMD : OUT_THRUST_CMD + 4]
    flags |= allocate(u1, u2, u3, u4, cp.arm_length, cp.km_over_kf, cp.f_max, cp.alloc_priority, forces)
    for i in range(4):
        cstate[CS_THRUST + i] = forces[i]
        v_cmd[i] = voltage_for_thrust(forces[i], cp.k_v, cp.v_max)
    record_decision(forces, flags, r0, r1, r2, dr0, dr1, dr2, s3, cp, cout)
    return flags


@jit(inline="always")
def record_decision(forces, flags, r0, r1, r2, dr0, dr1, dr2, s3, cp, cout):
    """Record in ``cout`` what the controller decided: u1..u4 of the motor thrusts ``forces``
    (A6), the attitude references, the sliding surfaces ``s3`` and the flags (shared by the
    built-in laws and the per-motor plug-in path)."""
    cout[OUT_U] = forces[0] + forces[1] + forces[2] + forces[3]
    cout[OUT_U + 1] = cp.arm_length * (forces[3] - forces[1])
    cout[OUT_U + 2] = cp.arm_length * (forces[0] - forces[2])
    cout[OUT_U + 3] = cp.km_over_kf * (forces[0] - forces[1] + forces[2] - forces[3])
    cout[OUT_ATT_DES] = r0
    cout[OUT_ATT_DES + 1] = r1
    cout[OUT_ATT_DES + 2] = r2
    cout[OUT_ATT_RATE_DES] = dr0
    cout[OUT_ATT_RATE_DES + 1] = dr1
    cout[OUT_ATT_RATE_DES + 2] = dr2
    cout[OUT_S] = s3[0]
    cout[OUT_S + 1] = s3[1]
    cout[OUT_S + 2] = s3[2]
    cout[OUT_FLAGS] = flags
