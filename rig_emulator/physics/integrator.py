"""Fixed-step fourth-order Runge-Kutta for the rig state, and the virtual ground."""

from rig_emulator._jit import jit
from rig_emulator.physics.hardware import motor_thrust
from rig_emulator.physics.rigid_body import state_derivative
from rig_emulator.physics.rotation import quat_normalize


@jit(nrt=False)
def rk4_step(t, h, x, v_cmd, p, wind, gusts, shocks, extra, work, R):
    """Advance ``x`` in place by one RK4 step of length ``h``.

    ``work`` is a (5, 17) scratch array (k1..k4 and the stage state): no allocation.
    With a zero motor time constant the motors follow their command at once.
    """
    n = x.shape[0]
    if p.tau_motor <= 0.0:
        for i in range(4):
            x[13 + i] = v_cmd[i]
    k1 = work[0]
    k2 = work[1]
    k3 = work[2]
    k4 = work[3]
    xs = work[4]
    state_derivative(t, x, v_cmd, p, wind, gusts, shocks, extra, R, k1)
    for i in range(n):
        xs[i] = x[i] + 0.5 * h * k1[i]
    state_derivative(t + 0.5 * h, xs, v_cmd, p, wind, gusts, shocks, extra, R, k2)
    for i in range(n):
        xs[i] = x[i] + 0.5 * h * k2[i]
    state_derivative(t + 0.5 * h, xs, v_cmd, p, wind, gusts, shocks, extra, R, k3)
    for i in range(n):
        xs[i] = x[i] + h * k3[i]
    state_derivative(t + h, xs, v_cmd, p, wind, gusts, shocks, extra, R, k4)
    sixth = h / 6.0
    for i in range(n):
        x[i] += sixth * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    quat_normalize(x[6:10])
    if p.ground and x[2] <= 0.0:
        apply_ground(x, p)


REST_THRUST_FRACTION = 0.05  # below this share of the weight a vehicle on the ground rests


@jit(nrt=False)
def apply_ground(x, p):
    """Virtual ground at Z = 0 (the paper's runs start on the ground): no sinking below it.

    Reading: the HILMS integrates a free-flying vehicle; the ground only keeps a thrust
    deficit at start-up from sending the virtual vehicle below its take-off altitude. It is
    frictionless, so a tilted thrust still moves the vehicle horizontally. Reading (issue 9):
    with the motors (nearly) stopped - total thrust below ``REST_THRUST_FRACTION`` of the
    weight, e.g. after a disarm or the loss-of-control failsafe - a vehicle on the ground
    rests instead of sliding on for ever.
    """
    if x[2] <= 0.0:
        x[2] = 0.0
        if x[5] < 0.0:
            x[5] = 0.0
        f = 0.0
        for i in range(4):
            f += motor_thrust(x[13 + i], i, p.k_v, p.f_ceiling, p.thrust_efficiency[i], p.hw)
        if f < REST_THRUST_FRACTION * p.mass * p.g:
            x[3] = 0.0
            x[4] = 0.0
