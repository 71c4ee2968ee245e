"""Fixed-step fourth-order Runge-Kutta for the rig state, and the virtual ground."""

from rig_emulator._jit import jit
from rig_emulator.physics.ground import hold_on_ground
from rig_emulator.physics.hardware import motor_thrust
from rig_emulator.physics.rigid_body import state_derivative
from rig_emulator.physics.rotation import quat_normalize


@jit(inline="always")  # one call site (the step loop): see the note below
def rk4_step(t, h, x, v_cmd, p, wind, gusts, shocks, extra, work, R):
    """Advance ``x`` in place by one RK4 step of length ``h``.

    ``work`` is a (5, 17) scratch array (k1..k4 and the stage state): no allocation.
    With a zero motor time constant the motors follow their command at once.

    Speed: this and :func:`state_derivative` are inlined into the step loop, the four stages
    through one call site. A call of a compiled function passes every field of every array
    and namedtuple argument one by one (numba flattens them), and ``p`` with its hardware
    parameters is some 130 values: as calls, the five per step cost the ideal plant about a
    fifth of its step (docs/explanation/performance.md, hardware-rig). The stage state of k1 is a copy
    of ``x`` (the same values), so the arithmetic is that of the four separate calls.
    """
    n = x.shape[0]
    x_before = x[0]  # the horizontal position a vehicle standing on the ground keeps (apply_ground)
    y_before = x[1]
    if p.tau_motor <= 0.0:
        for i in range(4):
            x[13 + i] = v_cmd[i]
    xs = work[4]
    for stage in range(4):
        if stage == 0:
            ts = t
            for i in range(n):
                xs[i] = x[i]
        elif stage == 3:
            ts = t + h
            k3 = work[2]
            for i in range(n):
                xs[i] = x[i] + h * k3[i]
        else:
            ts = t + 0.5 * h
            kp = work[stage - 1]
            for i in range(n):
                xs[i] = x[i] + 0.5 * h * kp[i]
        state_derivative(ts, xs, v_cmd, p, wind, gusts, shocks, extra, R, work[stage])
    k1 = work[0]
    k2 = work[1]
    k3 = work[2]
    k4 = work[3]
    sixth = h / 6.0
    for i in range(n):
        x[i] += sixth * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    quat_normalize(x[6:10])
    if p.ground and x[2] <= 0.0:
        apply_ground(x, p, x_before, y_before)


REST_THRUST_FRACTION = 0.05  # below this share of the weight a vehicle on the ground rests


@jit(nrt=False)
def apply_ground(x, p, x_before, y_before):
    """Virtual ground at Z = 0 (the paper's runs start on the ground): no sinking below it.

    Reading: the HILMS integrates a free-flying vehicle; the ground keeps a thrust deficit at
    start-up from sending the virtual vehicle below its take-off altitude. What else it does is
    ``sim.ground_contact`` (:mod:`rig_emulator.physics.ground`): with ``p.ground_hold`` (the
    hardware rig) a vehicle standing on it keeps its place (:func:`hold_on_ground`; ``x_before``,
    ``y_before``: the horizontal position at the start of the step). Without it (the ideal plant)
    the ground is frictionless, so a tilted thrust still moves the vehicle horizontally, and
    only with the motors (nearly) stopped - total thrust below ``REST_THRUST_FRACTION`` of the
    weight, e.g. after a disarm or the loss-of-control failsafe - does a vehicle on the ground
    rest instead of sliding on for ever.
    """
    if x[2] <= 0.0:
        x[2] = 0.0
        if x[5] < 0.0:
            x[5] = 0.0
        if p.ground_hold:
            hold_on_ground(x, x_before, y_before)
            return
        f = 0.0
        for i in range(4):
            f += motor_thrust(x[13 + i], i, p.k_v, p.f_ceiling, p.thrust_efficiency[i], p.hw)
        if f < REST_THRUST_FRACTION * p.mass * p.g:
            x[3] = 0.0
            x[4] = 0.0
