"""The compiled step loop: physics -> sensors -> estimation -> control -> actuators -> physics.

``run_steps`` advances the rig by ``n_steps`` physics steps starting at step ``k_start``
(time = k dt exactly, no accumulated rounding). Each step the sensors due at that step
are sampled from the current state and the estimators take them in; every ``ctrl_div``
steps guidance and control run on the feedback the config selects (the rig's estimates,
as on the hardware, or the true state) with a zero-order hold on the motor commands; a
log row is written every ``log_div`` steps. It can be called repeatedly on the same
arrays: a headless run calls it once, the MAVLink rig calls it in chunks. After every
``up.div``-th control update the supervisor (:mod:`rig_emulator.control.supervisor`) checks sensor
health and loss of control; when its failsafe disarms, the rest of the call runs disarmed
(the caller reads the latch and keeps the rig disarmed).

The controller (``pl``, ``pfn``; :mod:`rig_emulator.control.plugin_step`) is called the same
way whichever it is: the built-in strategy's kernel (:mod:`rig_emulator.controllers.builtin.kernel`),
a compiled plug-in or a Python one, each through the function pointer ``pfn``. With
``P_EXTERNAL`` no controller runs and the motor voltages ``v_cmd`` are whatever the caller set
(lockstep): ``pfn`` is None, and numba prunes the controller branch at compile time.

Reading: the accelerometers' lever-arm term uses the angular acceleration of the
previous step's first RK4 stage.
"""

from rig_emulator._jit import jit
from rig_emulator.control.supervisor import F_CELLS, F_FAILSAFE, F_INVALID, supervise
from rig_emulator.control.controller import (
    CS_STARTED,
    CS_TEST_UNTIL,
    CS_TEST_V,
    OUT_ATT_DES,
    OUT_ATT_RATE_DES,
    OUT_FLAGS,
    OUT_S,
    OUT_U,
    OUT_UXY,
    REF_MODE,
    REF_POS,
    REF_VEL,
)
from rig_emulator.control.plugin_layout import K_VOLTAGES
from rig_emulator.control.plugin_step import plugin_control
from rig_emulator.control.thrust_loop import thrust_loop
from rig_emulator.estimation.attitude_pipeline import attitude_estimation_step
from rig_emulator.estimation.load_cell_filter import load_cell_filter_step
from rig_emulator.estimation.onboard_position import onboard_translation_step
from rig_emulator.guidance.runner import GS_INDEX, guidance_update
from rig_emulator.physics.disturbances import wind_force
from rig_emulator.physics.integrator import rk4_step
from rig_emulator.physics.hardware import (actuator_chain, frame_vibration_step, motor_field_step, motor_thrust,
                                           torque_noise_step)
from rig_emulator.physics.motors import rotor_speed
from rig_emulator.physics.rotation import euler_from_quat, euler_rates_from_body_rates
from rig_emulator.sensors.sensor_step import SAMPLED_CELLS, sensors_step
from rig_emulator.simulation import log_layout as L
from rig_emulator.simulation.rng_bits import generator


# inlined: one call site, and a call passes pp, sp and ss field by field (hundreds of values) every step
@jit(inline="always")
def _sense(k, x, pp, sp, ss, rng, omega_dot):
    """Sample the sensors due at step k and run the estimators on them."""
    if k % sp.suite.cells.decim == 0:  # the load cells need the motors' thrusts and speeds
        for i in range(4):
            f = motor_thrust(x[13 + i], i, pp.k_v, pp.f_ceiling, pp.thrust_efficiency[i], pp.hw)
            ss.thrust_true[i] = f
            ss.rotor_speed[i] = rotor_speed(f, pp.kf)
    if pp.hw.vib_on and k % sp.suite.imu.decim_inertial == 0:  # frame vibration, all modules alike
        frame_vibration_step(sp.suite.imu.dt_s * sp.suite.imu.decim_inertial, x, pp, ss.sstate.frame_vibration)
    # the motor currents' field at the magnetometers, all modules alike
    if (pp.hw.mag_ripple > 0.0 or pp.hw.mag_steady > 0.0) and k % sp.suite.imu.decim_mag == 0:
        motor_field_step(x, pp, ss.sstate.motor_field)
    mask = sensors_step(k, x[6:10], x[10:13], omega_dot, ss.thrust_true, ss.rotor_speed,
                        sp.suite, ss.sstate, rng, ss.imu_raw, ss.cell_raw)
    if mask == 0:
        return
    ss.health[0] = attitude_estimation_step(mask, ss.imu_raw, sp.chain, ss.awork, ss.att_est)
    if mask & SAMPLED_CELLS:
        ss.health[1] = load_cell_filter_step(ss.cell_raw, sp.lcp, ss.lcs, ss.thrust_est)


@jit(nrt=False, python=True)  # Python's entry point; see rig_emulator/simulation/rng_bits.py for rng_bits
def run_steps(
    k_start, n_steps, dt, ctrl_div, log_div,
    x, v_cmd, pp, cp, gp, wind, gusts, shocks, extra,
    cstate, gstate, reached_t, ref, cout, scratch, work, R, log, log_row, armed,
    sp, ss, rng_bits, up, us, pl, pfn,
):
    """Advance the rig; returns the next free log row.

    Disarmed, the motors are commanded to 0 V and the controller is reset so that it
    starts afresh on arming.

    Compiled without reference counting (no allocation here), so the sensors' generator
    comes as its bit generator's pointers ``rng_bits`` (``rng_bits.pointers(rng.bit_generator)``),
    not as the Generator.
    """
    rng = generator(rng_bits)
    ctrl_dt = dt * ctrl_div
    phi = 0.0
    theta = 0.0
    psi = 0.0
    for k in range(k_start, k_start + n_steps):
        t = k * dt
        if sp.simulate and (k % sp.suite.imu.decim_inertial == 0 or k % sp.suite.imu.decim_mag == 0
                            or k % sp.suite.cells.decim == 0):
            _sense(k, x, pp, sp, ss, rng, work[0, 10:13])
        if not armed:
            for i in range(4):  # 0 V, or a motor test's voltage (DO_MOTOR_TEST, LiveRig.motor_test)
                v_cmd[i] = cstate[CS_TEST_V + i] if t < cstate[CS_TEST_UNTIL] else 0.0
            cstate[CS_STARTED] = 0.0
        if k % ctrl_div == 0:
            if sp.simulate:
                fwx, fwy, fwz = wind_force(t, wind, gusts)
                u1_meas = ss.thrust_est[0] + ss.thrust_est[1] + ss.thrust_est[2] + ss.thrust_est[3]
                onboard_translation_step(ctrl_dt, ss.att_est[0], ss.att_est[1], ss.att_est[2], u1_meas,
                                         pp.mass, pp.g, fwx, fwy, fwz, pp.ground, pp.ground_hold, ss.onboard)
            if sp.estimated:
                phi = ss.att_est[0]
                theta = ss.att_est[1]
                psi = ss.att_est[2]
                dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, ss.att_est[3], ss.att_est[4], ss.att_est[5])
                pos = ss.onboard[0:3]
                vel = ss.onboard[3:6]
                wx = ss.att_est[3]
                wy = ss.att_est[4]
                wz = ss.att_est[5]
            else:
                phi, theta, psi = euler_from_quat(x[6], x[7], x[8], x[9])
                dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, x[10], x[11], x[12])
                pos = x[0:3]
                vel = x[3:6]
                wx = x[10]
                wy = x[11]
                wz = x[12]
            if armed:
                guidance_update(t, pos, gp, gstate, reached_t, ref)
                eq40 = False  # did the motor commands go through the firmware's Eq. 40 inverse?
                if pfn is not None:  # every controller, the built-in strategy's kernel among them; without
                    # one (P_EXTERNAL: v_cmd set from outside) pfn is None and numba drops this branch
                    if not plugin_control(k, t, dt, ctrl_dt, pos, vel, phi, theta, psi, dphi, dtheta, dpsi, wx, wy, wz,
                                          ref, pp, cp, cstate, cout, v_cmd, scratch, x, sp, ss, pl, pfn):
                        armed = False  # the controller failed: motors off from the next step (pl.status says why)
                    else:
                        eq40 = pl.kind != K_VOLTAGES  # a plug-in's voltages bypass it
                if eq40 and cp.thrust_loop_rate > 0.0 and sp.simulate:  # Sec. 3-3's load-cell thrust loop
                    thrust_loop(ctrl_dt, cp, cstate, cout, ss.thrust_est, us.flags[F_CELLS], v_cmd)
            if k % up.div == 0 and supervise(t, armed, sp.simulate, sp.estimated, phi, theta, wx, wy, wz, cout,
                                             ss.awork.ensemble.rejected, ss.awork.combined, ss.health[1], up, us):
                armed = False  # the failsafe cuts the motors from the next step on
        if k % log_div == 0 and log_row < log.shape[0]:
            _log_row(log[log_row], t, x, pp, sp, ss, ref, cout, gstate, v_cmd, us)
            log_row += 1
        # the command reaches the motors through the ESC chain (delay, quantisation,
        # dead-band; v_cmd itself in the ideal plant), the random body torque is held over the step
        torque_noise_step(x, pp)
        rk4_step(t, dt, x, actuator_chain(k, v_cmd, pp.hw), pp, wind, gusts, shocks, extra, work, R)
    return log_row


@jit(nrt=False)
def _log_row(row, t, x, pp, sp, ss, ref, cout, gstate, v_cmd, us):
    phi, theta, psi = euler_from_quat(x[6], x[7], x[8], x[9])
    row[L.T] = t
    row[L.EULER_TRUE] = phi
    row[L.EULER_TRUE + 1] = theta
    row[L.EULER_TRUE + 2] = psi
    if sp.estimated:
        phi = ss.att_est[0]
        theta = ss.att_est[1]
        psi = ss.att_est[2]
        dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, ss.att_est[3], ss.att_est[4], ss.att_est[5])
    else:
        dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, x[10], x[11], x[12])
    for i in range(3):
        row[L.POS + i] = ss.onboard[i] if sp.estimated else x[i]
        row[L.VEL + i] = ss.onboard[3 + i] if sp.estimated else x[3 + i]
        row[L.POS_TRUE + i] = x[i]
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
        row[L.THRUST + i] = motor_thrust(x[13 + i], i, pp.k_v, pp.f_ceiling, pp.thrust_efficiency[i], pp.hw)
        row[L.V_CMD + i] = v_cmd[i]
        row[L.U + i] = cout[OUT_U + i]
        row[L.THRUST_MEAS + i] = ss.thrust_est[i] if sp.simulate else row[L.THRUST + i]
    row[L.FLAGS] = cout[OUT_FLAGS]
    row[L.WAYPOINT] = gstate[GS_INDEX]
    row[L.MODE] = ref[REF_MODE]
    row[L.UXY] = cout[OUT_UXY]
    row[L.UXY + 1] = cout[OUT_UXY + 1]
    row[L.HEALTH] = ss.health[0]
    row[L.HEALTH + 1] = ss.health[1]
    row[L.FAILSAFE] = us.flags[F_FAILSAFE]
    row[L.ESTIMATE_INVALID] = us.flags[F_INVALID]
