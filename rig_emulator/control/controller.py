"""One control update: guidance references in, motor voltage commands out.

Flow (Fig. 7): position law -> (u1, uX, uY) -> Eq. 35 -> desired attitude -> reference
filter -> attitude law -> Euler-frame torques -> body torques -> allocation (A6 inverse)
-> motor voltages (Eq. 40 inverse). In attitude mode (the paper's attitude experiments)
the references come straight from guidance and u1 is the hover thrust m g.

Layouts:

* ``ref`` (from guidance, see guidance/runner.py): REF_* indices below.
* ``cstate`` (controller memory): CS_* indices.
* ``cout`` (what the controller decided, for logs and telemetry): OUT_* indices.
"""

from rig_emulator._jit import jit
from rig_emulator.control.allocation import allocate, euler_torque_to_body
from rig_emulator.control.fuzzy import flc_axis
from rig_emulator.control.pid import pid_axis
from rig_emulator.control.reference_filter import reference_step, wrap_angle
from rig_emulator.control.smc import smc_attitude, switch
from rig_emulator.control.strategies import FLC, SMC
from rig_emulator.control.thrust_direction import collective_thrust, desired_tilt
from rig_emulator.physics.motors import rotor_speed, voltage_for_thrust

# guidance output
REF_MODE = 0  # 0: position references, 1: attitude references
REF_POS = 1
REF_VEL = 4
REF_ACC = 7
REF_YAW = 10
REF_ATT = 11
REF_ATT_RATE = 14
REF_ATT_ACC = 17
REF_SIZE = 20
MODE_POSITION = 0.0
MODE_ATTITUDE = 1.0

# controller memory
CS_FILTER = 0  # 6: (value, rate) of the phi, theta, psi reference filters
CS_ATT_INT = 6  # 3: attitude PID integrators
CS_POS_INT = 9  # 3: position PID integrators
CS_THRUST = 12  # 4: last commanded thrusts (N), for the rotor gyroscopic estimate
CS_STARTED = 16  # 1: 0 until the first update has initialised the filters
# actuator test, not controller state: DO_MOTOR_TEST spins motors while disarmed (simulation/live.py motor_test)
CS_TEST_V = 17  # 4: voltage commanded to each motor during the test
CS_TEST_UNTIL = 21  # 1: the test ends at this time (s)
CS_SIZE = 22

# controller output
OUT_U = 0  # 4: u1 (N), u2, u3, u4 (N m, body axes, as allocated)
OUT_ATT_DES = 4  # 3: desired phi, theta, psi
OUT_ATT_RATE_DES = 7  # 3
OUT_S = 10  # 3: sliding surfaces s = e' + lambda e
OUT_FLAGS = 13  # allocation SATURATED_* | TILT_CLAMPED
OUT_THRUST_CMD = 14  # 4: commanded thrusts (N)
OUT_UXY = 18  # 2: virtual inputs uX, uY (Eq. 34)
OUT_SIZE = 20


@jit(nrt=False)
def control_update(dt, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz, ref, cp, cstate, cout, v_cmd, e3, de3, acc3, s3, tau3):
    """Run one controller update. ``e3, de3, acc3, s3, tau3`` are (3,) scratch arrays."""
    flags = 0
    if ref[REF_MODE] == MODE_POSITION:
        ex = ref[REF_POS] - pos[0]
        ey = ref[REF_POS + 1] - pos[1]
        ez = ref[REF_POS + 2] - pos[2]
        dex = ref[REF_VEL] - vel[0]
        dey = ref[REF_VEL + 1] - vel[1]
        dez = ref[REF_VEL + 2] - vel[2]
        weight = cp.mass * cp.g
        if cp.pos_law == FLC:
            # Eq. 37: uX, uY and the altitude correction of u1 from three fuzzy axes
            ux = flc_axis(ex, dex, cp.flc_x, cp.rule_table)
            uy = flc_axis(ey, dey, cp.flc_y, cp.rule_table)
            vertical = weight + flc_axis(ez, dez, cp.flc_z, cp.rule_table)
            u1 = collective_thrust(vertical, phi, theta, cp.max_tilt)
        else:
            if cp.pos_law == SMC:
                ax = ref[REF_ACC] + cp.smcp_lam[0] * dex + cp.smcp_k[0] * switch(dex + cp.smcp_lam[0] * ex, True, cp.smcp_phi)
                ay = ref[REF_ACC + 1] + cp.smcp_lam[1] * dey + cp.smcp_k[1] * switch(dey + cp.smcp_lam[1] * ey, True, cp.smcp_phi)
                az = ref[REF_ACC + 2] + cp.smcp_lam[2] * dez + cp.smcp_k[2] * switch(dez + cp.smcp_lam[2] * ez, True, cp.smcp_phi)
            else:
                integ = cstate[CS_POS_INT : CS_POS_INT + 3]
                ax = pid_axis(ex, dex, ref[REF_ACC], cp.pidp_kp[0], cp.pidp_ki[0], cp.pidp_kd[0], integ, 0, dt, cp.pid_limit)
                ay = pid_axis(ey, dey, ref[REF_ACC + 1], cp.pidp_kp[1], cp.pidp_ki[1], cp.pidp_kd[1], integ, 1, dt, cp.pid_limit)
                az = pid_axis(ez, dez, ref[REF_ACC + 2], cp.pidp_kp[2], cp.pidp_ki[2], cp.pidp_kd[2], integ, 2, dt, cp.pid_limit)
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
        if cstate[CS_STARTED] == 0.0:
            cstate[CS_FILTER + 0] = phi_d
            cstate[CS_FILTER + 2] = theta_d
            cstate[CS_FILTER + 4] = psi_d
        r0, dr0, a0 = reference_step(phi_d, cstate, 0, cp.ref_omega, dt, False)
        r1, dr1, a1 = reference_step(theta_d, cstate, 1, cp.ref_omega, dt, False)
        r2, dr2, a2 = reference_step(psi_d, cstate, 2, cp.ref_omega, dt, True)
    else:
        u1 = cp.mass * cp.g
        cout[OUT_UXY] = 0.0
        cout[OUT_UXY + 1] = 0.0
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
            tau3[0] = cp.ixx * pid_axis(e3[0], de3[0], a0, cp.pida_kp[0], cp.pida_ki[0], cp.pida_kd[0], integ, 0, dt, cp.pid_limit)
            tau3[1] = cp.iyy * pid_axis(e3[1], de3[1], a1, cp.pida_kp[1], cp.pida_ki[1], cp.pida_kd[1], integ, 1, dt, cp.pid_limit)
            tau3[2] = cp.izz * pid_axis(e3[2], de3[2], a2, cp.pida_kp[2], cp.pida_ki[2], cp.pida_kd[2], integ, 2, dt, cp.pid_limit)

    u2, u3, u4 = euler_torque_to_body(tau3[0], tau3[1], tau3[2])
    forces = cout[OUT_THRUST_CMD : OUT_THRUST_CMD + 4]
    flags |= allocate(u1, u2, u3, u4, cp.arm_length, cp.km_over_kf, cp.f_max, forces)
    for i in range(4):
        cstate[CS_THRUST + i] = forces[i]
        v_cmd[i] = voltage_for_thrust(forces[i], cp.k_v, cp.v_max)
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
    return flags
