"""The firmware's load-cell thrust loop (a reading of Sec. 3-3; off by default).

Sec. 3-3: "using the output of the force sensors and Eq. 40, the input voltage of the motors
and consequently the resulted PWM signal is computed". Read as an open-loop inverse of Eq. 40
(the default, ``motors.thrust_loop_time_constant = 0``) the load cells only feed Eq. 1's
virtual translation. Read as a closed thrust loop (:func:`thrust_loop`), the onboard computer
also compares each motor's desired thrust with its filtered load-cell thrust and corrects the
voltage it commands, slowly: a common thrust-chain bias (Eq. 40's fit overstating the running
thrust) or a motor's gain error then goes away at the loop's time constant, and the load cells'
filter (IIR) sits inside a feedback path. The paper publishes no time constant.
"""

from rig_emulator._jit import jit
from rig_emulator.control.controller import CS_THRUST_CORR, OUT_THRUST_CMD
from rig_emulator.physics.motors import voltage_for_thrust


@jit(inline="always")
def thrust_loop(dt, cp, cstate, cout, thrust_meas, cells_flagged, v_cmd):
    """Close each motor's thrust on its filtered load cell (Sec. 3-3 with Eq. 40); rewrites ``v_cmd``.

    Where it acts: on the motor voltage commands, after the allocation (A6 inverse) and the
    Eq. 40 inverse of :func:`rig_emulator.control.controller.actuate`, before the actuator chain
    (delay, quantisation, dead-band); after every controller whose command went through that Eq. 40
    inverse, the built-in strategies' kernel among them (not a plug-in that commands voltages, nor
    an external motor source such as the PX4 lockstep). Fed by what the onboard computer has: the desired thrusts
    ``cout[OUT_THRUST_CMD:+4]`` (N) and the load cells' filtered thrusts ``thrust_meas`` (N; the
    output of the filter ``estimation.load_cell_filter`` selects, the same series Eq. 1's
    virtual altitude integrates).

    Per motor ``i`` the correction ``c_i`` (N, ``cstate[CS_THRUST_CORR + i]``) integrates the
    thrust error, ``c_i += (dt / T) (F_des,i - F_meas,i)``, and the command is
    ``V_i = Eq. 40^-1(F_des,i + c_i)`` (the controllers' Eq. 40 slope, clipped to the supply).
    ``T`` is ``motors.thrust_loop_time_constant`` (``cp.thrust_loop_rate = 1 / T``): on a motor
    whose true thrust is Eq. 40's plus a constant bias the bias decays as ``exp(-t / T)``; where
    the true curve is steeper than Eq. 40 by a factor ``n`` (the convex curve at hover) it decays
    at ``T / n``.

    Bounded, so that a faulted load cell cannot run it away: ``|c_i|`` is held within
    ``cp.thrust_loop_limit`` (``motors.thrust_loop_limit_grf``); the correction of a cell the
    supervisor flags (bit ``i`` of ``cells_flagged``: a dead cell, rejected by the guards) is
    frozen until it is healthy again; a motor commanded off stays off and its correction is held.
    A stuck cell, which no guard can see (docs/how-to/faults.md), drives its correction at most to the
    limit. The bound is the only anti-windup: freezing the integrator while a command is clipped
    at the supply would leave out the samples where the SMC's relay (Fig. 18) pushes a motor to
    the ceiling, whose error is one-signed, and leave a mean thrust error (measured: 0.5 N of
    u1 in hover). The correction is the firmware's memory of its thrust chain: it is kept through
    a disarm.
    """
    gain = dt * cp.thrust_loop_rate
    lim = cp.thrust_loop_limit
    for i in range(4):
        f_des = cout[OUT_THRUST_CMD + i]
        if f_des <= 0.0:
            continue  # commanded off: stays off (0 V from actuate), the correction is held
        c = cstate[CS_THRUST_CORR + i]
        if ((cells_flagged >> i) & 1) == 0:
            c += gain * (f_des - thrust_meas[i])
            if c > lim:
                c = lim
            elif c < -lim:
                c = -lim
            cstate[CS_THRUST_CORR + i] = c
        v_cmd[i] = voltage_for_thrust(f_des + c, cp.k_v, cp.v_max)
