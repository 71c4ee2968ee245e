"""The real rig's departures from the ideal plant: one named function per effect.

Every effect has a neutral value that leaves the ideal plant of Eq. 1-3 and Eq. 40 exactly
as it was (the ``hilms-ideal`` airframe uses only neutral values, bit for bit); the
``hilms`` airframe selects ``presets/hardware/hilms.toml`` with values a real rig of this
build plausibly has. Parameters come in :class:`HardwareParams` (``PhysicsParams.hw``),
state in its arrays (allocated once; nothing here allocates). Where each acts:

==============================  =====================================  ==========================================
effect (function)               acts on                                parameters (config keys)
==============================  =====================================  ==========================================
:func:`joint_friction_torque`   Eq. 3, body torque                     ``joint.viscous``, ``joint.coulomb``,
                                                                       ``joint.coulomb_smoothing``
:func:`cog_gravity_torque`      Eq. 3, body torque                     ``joint.cog_offset``
:func:`motor_thrust`            Eq. 40, each motor's true thrust       ``motors.thrust_gain``,
                                (physics, load cells, logs)            ``motors.thrust_bias_grf``,
                                                                       ``motors.curve_exponent``,
                                                                       ``motors.curve_pivot_grf``
:func:`actuator_chain`          voltage command -> motor (each step)   ``control.actuation_delay``,
                                                                       ``motors.command_steps``,
                                                                       ``motors.esc_deadband_v``
:func:`torque_noise_step`       Eq. 3, body torque held over a step    ``disturbance.torque_noise``,
                                                                       ``disturbance.torque_noise_corner_hz``
:func:`frame_vibration_step`    IMU gyro and accelerometer inputs,     ``vibration.gyro_amplitude``,
                                the same on all five modules           ``vibration.accel_amplitude``,
                                                                       ``vibration.blades``
:func:`motor_field_step`        magnetometer inputs, the same on all   ``motor_field.ripple_uT``,
                                five modules                           ``motor_field.steady_uT``
==============================  =====================================  ==========================================

Model mismatch (``controller_model.*``) and the position FLC's rate input
(``flc.position_rate_share``) are controller-side: :mod:`rig_emulator.simulation.params`.
Sources of the magnitudes are given per function and in docs/explanation/readings.md.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit

HardwareParams = namedtuple(
    "HardwareParams",
    [
        "friction",        # bool: any joint friction
        "visc",            # (3,) viscous joint friction per body axis, N m s/rad
        "coul",            # (3,) Coulomb joint friction per body axis, N m
        "coul_rate",       # rate below which the Coulomb term is smoothed (tanh), rad/s
        "cog_on",          # bool
        "cog_moment",      # (3,) m_rig * r_cg in B (FRD), kg m: gravity torque = r_cg x (m g_B)
        "gain",            # (4,) per-motor thrust gain x common thrust-chain gain
        "bias",            # common additive thrust bias of a running motor, N
        "curve_n",         # exponent of the true motor curve (1: Eq. 40)
        "curve_vp",        # pivot voltage where the true curve meets Eq. 40, V
        "curve_fp",        # pivot thrust, N
        "act_on",          # bool: delay, quantisation or dead-band present
        "delay_steps",     # int: sensing-to-actuation delay in physics steps
        "cmd_buf",         # (delay_steps + 1, 4) ring buffer of voltage commands
        "cmd_out",         # (4,) the voltages the motors receive this step
        "quantum",         # ESC command quantum, V (0: continuous)
        "deadband",        # ESC dead-band, V (commands below give 0 V)
        "noise_on",        # bool
        "noise_sigma",     # (3,) std of the coloured body torque, N m
        "noise_a",         # first-order filter pole per physics step, exp(-2 pi fc dt)
        "noise_b",         # sqrt(1 - a^2): keeps the filtered std at sigma
        "noise_torque",    # (3,) the torque held over the current step, N m (state)
        "rng",             # (1,) uint64 splitmix64 state, seeded from sim.seed
        "vib_on",          # bool
        "vib_gyro",        # (3,) per-rotor gyro vibration amplitude at hover rotor speed, rad/s
        "vib_acc",         # (3,) per-rotor accelerometer vibration amplitude at hover rotor speed, m/s^2
        "vib_blades",      # blades per rotor (the blade-pass frequency is blades x rotor speed)
        "vib_omega_ref",   # hover rotor speed, rad/s (amplitudes scale with (Omega / this)^2)
        "vib_phase",       # (4,) blade-pass phase of each rotor, rad (state)
        "mag_ripple",      # rms field per motor per magnetometer sample at hover current, T (0: off)
        "mag_steady",      # steady field per motor at hover current, T (0: off)
        "curve_memo",      # (4, 2) per motor the last (V / V_p, (V / V_p)^n) of motor_thrust (a cache; new with n)
    ],
)


def neutral_arrays():
    """State arrays of a plant with no effects (shape-compatible with any HardwareParams)."""
    return dict(cmd_buf=np.zeros((1, 4)), cmd_out=np.zeros(4), noise_torque=np.zeros(3),
                rng=np.zeros(1, dtype=np.uint64), vib_phase=np.zeros(4), curve_memo=np.full((4, 2), np.nan))


# --- joint --------------------------------------------------------------------------------


@jit(inline="always")
def joint_friction_torque(wx, wy, wz, hw):
    """Friction torque of the spherical joint on the body (B), added to Eq. 3's torques.

    Per body axis ``-c_v w - c_c tanh(w / w_s)``: viscous plus Coulomb friction, the
    Coulomb step smoothed over ``w_s`` (``joint.coulomb_smoothing``) so that RK4 sees a
    continuous right-hand side and a rig at rest stays at rest. Magnitude: a greased ball
    joint of this size (about 20 mm ball, 2.2 kg on it) has a breakaway torque of the
    order of 0.01-0.05 N m; the viscous part (cable drag, grease) 0.005-0.05 N m s/rad.
    Source: the rig's Fig. 12 responses settle without limit cycles (RIG-SPEC), and a
    failsafe trip must be recoverable: without friction a disarmed rig spins
    for ever.
    """
    if not hw.friction:
        return 0.0, 0.0, 0.0
    v = hw.visc
    c = hw.coul
    s = hw.coul_rate
    return (-v[0] * wx - c[0] * math.tanh(wx / s),
            -v[1] * wy - c[1] * math.tanh(wy / s),
            -v[2] * wz - c[2] * math.tanh(wz / s))


@jit(inline="always")
def cog_gravity_torque(R, hw, g):
    """Gravity torque of the rig's centre of gravity away from the pivot (B), Eq. 3.

    ``tau = r_cg x (m R_WB^T (0, 0, -g))`` with ``r_cg`` (``joint.cog_offset``, B = FRD)
    the centre of gravity relative to the joint: a lateral offset (x, y) is a static
    imbalance the controllers must hold against (it tilts the rig when disarmed); z > 0
    (below the joint) makes a stable pendulum, z < 0 (above) an inverted one. Magnitude:
    a few millimetres of assembly tolerance (battery, cables, the ball joint's seat) on
    2.23 kg give 0.02-0.1 N m; the extra masses of Fig. 15 are the same physics
    (``disturbances.extra_mass_effects``).
    """
    if not hw.cog_on:
        return 0.0, 0.0, 0.0
    m = hw.cog_moment
    fx = -g * R[2, 0]
    fy = -g * R[2, 1]
    fz = -g * R[2, 2]
    return (m[1] * fz - m[2] * fy,
            m[2] * fx - m[0] * fz,
            m[0] * fy - m[1] * fx)


def rest_attitude(hw, g, psi=0.0):
    """The attitude ``(phi, theta)`` (rad) at which a disarmed rig hangs still with yaw ``psi``:
    where :func:`cog_gravity_torque` vanishes with the centre of gravity straight below the
    joint (the stable equilibrium of the pendulum, Eq. 3 with no thrust). ``None`` when the
    centre of gravity is on the joint (any attitude is at rest: the ideal plant) or above it
    (no hanging rest: the rig tips over to its mechanical stop). Found numerically from level
    with this module's own torque, so it holds whatever the frame conventions."""
    from scipy.optimize import least_squares

    from rig_emulator.physics.rotation import quat_from_euler, quat_to_rot

    if not hw.cog_on:
        return None
    q = np.zeros(4)
    R = np.zeros((3, 3))

    def rotation(a):
        quat_from_euler(a[0], a[1], psi, q)
        quat_to_rot(q[0], q[1], q[2], q[3], R)
        return R

    def torque(a):
        return np.array(cog_gravity_torque(rotation(a), hw, g))

    sol = least_squares(torque, np.zeros(2), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    r = hw.cog_moment / np.linalg.norm(hw.cog_moment)
    if not (np.max(np.abs(torque(sol.x))) < 1e-9 and rotation(sol.x)[2] @ r < -0.999
            and max(abs(sol.x[0]), abs(sol.x[1])) < 0.5 * math.pi):
        return None  # the equilibrium found is not the hanging one: the CoG is above the joint
    return float(sol.x[0]), float(sol.x[1])


# --- motors -------------------------------------------------------------------------------


@jit(inline="always")
def motor_thrust(v, i, k_v, f_ceiling, efficiency, hw):
    """True thrust (N) of motor ``i`` at effective voltage ``v``: Eq. 40 as the hardware has it.

    * the curve: Eq. 40, ``F = k_v V``, is the rig's linear fit (Fig. 11). A propeller's
      thrust grows about as ``Omega^2`` and a BLDC's speed about as ``V``: the real curve
      is convex. Reading: ``F = F_p (V / V_p)^n`` through the pivot ``(V_p, F_p)`` where it
      meets Eq. 40 (``motors.curve_pivot_grf``, default the hover thrust); ``n = 1`` is
      Eq. 40. The controllers keep inverting Eq. 40 (they do not know the curve). With
      ``n = ln(850 / 557.7) / ln(15 / 11.71) = 1.70`` the 850 gr.F of Sec. 3-2 is reached at
      15 V (the paper's Eq. 40 gives 714 gr.F there): one reading of that inconsistency;
    * ``hw.gain[i]``: per-motor gain times the common thrust-chain gain
      (``motors.thrust_gain``), e.g. motors and propellers differing by a few per cent;
    * ``hw.bias``: a common additive thrust bias of a running motor (``motors.thrust_bias_grf``);
    * ``efficiency``: a motor fault's share (sensors/faults.py);
    * clipped to ``[0, f_ceiling]`` (850 gr.F, Sec. 3-2).
    """
    if hw.curve_n == 1.0 or v <= 0.0:
        f = k_v * v
    else:
        # the power is a libm call (pow), the hardware rig's most expensive per step; a step asks for
        # the thrust at the same voltage several times (vibration, load cells, log, the first RK4
        # stage), so the last power per motor is kept: the same inputs give the same bits (a memo is
        # new with every HardwareParams, simulation/params.py, so its exponent is fixed)
        r = v / hw.curve_vp
        memo = hw.curve_memo
        if r == memo[i, 0]:
            pw = memo[i, 1]
        else:
            pw = r ** hw.curve_n
            memo[i, 0] = r
            memo[i, 1] = pw
        f = hw.curve_fp * pw
    if hw.bias != 0.0 and v > 0.0:
        f += hw.bias
    if f < 0.0:
        f = 0.0
    elif f > f_ceiling:
        f = f_ceiling
    return efficiency * (hw.gain[i] * f)


@jit(inline="always")
def actuator_chain(k, v_cmd, hw):
    """The voltages the motors receive at physics step ``k`` for the commands ``v_cmd``.

    * sensing-to-actuation delay: the firmware's computation (the fuzzy controller on a
      72 MHz STM32 takes a good part of a 2 ms control period), the PWM frame and the ESC's
      own update: ``control.actuation_delay`` seconds, rounded to physics steps; a ring
      buffer of the last commands;
    * ESC command quantisation: ``motors.command_steps`` levels over the supply (a
      1000-2000 us servo pulse read with 1 us resolution has 1000);
    * ESC dead-band: commands below ``motors.esc_deadband_v`` give 0 V (the motor does not
      start below a minimum throttle).

    Returns ``v_cmd`` itself when none is configured (the ideal plant).
    """
    if not hw.act_on:
        return v_cmd
    buf = hw.cmd_buf
    n = buf.shape[0]
    row = k % n
    for j in range(4):
        buf[row, j] = v_cmd[j]
    src = (k - hw.delay_steps) % n
    out = hw.cmd_out
    for j in range(4):
        v = buf[src, j]
        if hw.quantum > 0.0:
            v = math.floor(v / hw.quantum + 0.5) * hw.quantum
        if v < hw.deadband:
            v = 0.0
        out[j] = v
    return out


# --- random body torque -------------------------------------------------------------------


@jit(inline="always")
def _uniform(state):
    """splitmix64: the next uniform in (0, 1) from ``state[0]`` (deterministic, allocation-free)."""
    z = state[0] + np.uint64(0x9E3779B97F4A7C15)
    state[0] = z
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return ((z >> np.uint64(11)) + 0.5) * (1.0 / 9007199254740992.0)


@jit(inline="always")
def _normal(state):
    """A standard normal by Box-Muller from two splitmix64 uniforms."""
    u1 = _uniform(state)
    u2 = _uniform(state)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@jit(inline="always")
def torque_noise_step(x, pp):
    """Advance the random body torque by one physics step (held over the step, Eq. 3).

    Prop wash of the four rotors on the arms and the drag of the sensor and power cables
    in that wash act as a random torque: first-order coloured noise with corner
    ``disturbance.torque_noise_corner_hz`` and standard deviation
    ``disturbance.torque_noise`` per body axis at hover,
    ``n_k = a n_{k-1} + b sigma L_k w_k`` (``a = exp(-2 pi f_c dt)``,
    ``b = sqrt(1 - a^2)``), ``w_k`` standard normal from a splitmix64 stream seeded by
    ``sim.seed``. ``L_k``, the rotor load, is the motors' thrust by Eq. 40 over the hover
    thrust ``m g`` (the wash's dynamic pressure grows with the induced velocity squared, i.e.
    with thrust): the torque is ``sigma`` at hover and dies out with the filter's time constant
    once the motors stop, so a disarmed rig hangs still on its joint. Magnitude: a few per
    cent of the hover torque authority; the paper's Fig. 12 traces wander by about
    0.5-1 deg between shocks. ``x`` is the rig state (motor voltages in ``x[13:17]``),
    ``pp`` the PhysicsParams.
    """
    hw = pp.hw
    if not hw.noise_on:
        return
    # the rotor load from the motor voltages through Eq. 40 (an estimate of the wash's size,
    # which keeps this per-step function free of the true curve's powers)
    load = pp.k_v * (x[13] + x[14] + x[15] + x[16]) / (pp.mass * pp.g)
    a = hw.noise_a
    b = hw.noise_b * load
    for i in range(3):
        hw.noise_torque[i] = a * hw.noise_torque[i] + b * hw.noise_sigma[i] * _normal(hw.rng)


# --- frame vibration ----------------------------------------------------------------------


@jit(inline="always")
def frame_vibration_step(dt, x, pp, vib_out):
    """Frame vibration at the IMU modules (B): gyro (0:3, rad/s) and accelerometer (3:6, m/s^2).

    Each rotor's blade-pass excitation ``A (Omega_i / Omega_hover)^2 sin(phase_i)``,
    ``phase_i`` advancing at ``blades x Omega_i`` (``Omega_i`` from the motor's true thrust,
    Eq. 38); the frame carries it to all five modules alike, so the ensemble (Sec. 4-1)
    cannot average it away. Magnitude: unbalanced 10-inch propellers on a light frame give
    0.5-3 m/s^2 and 0.01-0.05 rad/s at the IMU (typical flight-controller vibration logs);
    the load cells' own vibration noise is modelled in sensors/load_cell.py. ``x`` is the
    rig state, ``pp`` the PhysicsParams; advances the phases by ``dt`` (the IMU period).
    """
    hw = pp.hw
    for j in range(6):
        vib_out[j] = 0.0
    if not hw.vib_on:
        return
    for i in range(4):
        f = motor_thrust(x[13 + i], i, pp.k_v, pp.f_ceiling, pp.thrust_efficiency[i], hw)
        w = math.sqrt(f / pp.kf) if f > 0.0 else 0.0
        ph = hw.vib_phase[i] + hw.vib_blades * w * dt
        hw.vib_phase[i] = ph - 2.0 * math.pi * math.floor(ph / (2.0 * math.pi))
        r = w / hw.vib_omega_ref
        s = r * r * math.sin(hw.vib_phase[i])
        for j in range(3):
            vib_out[j] += hw.vib_gyro[j] * s
            vib_out[3 + j] += hw.vib_acc[j] * s


# --- magnetic field of the motor currents ------------------------------------------------

# Unit vector in B (FRD) of the field at the hub of the supply leads running along arm i (A6
# numbering minus one, arms along +x, +y, -x, -y: rigid_body.py): horizontal and perpendicular to
# the arm (Biot-Savart), z_B x a_i; opposite arms carry their currents in opposite senses, so at
# equal currents their steady fields cancel.
_LEAD_FIELD_X = (0.0, -1.0, 0.0, 1.0)
_LEAD_FIELD_Y = (1.0, 0.0, -1.0, 0.0)


# a call, not inline="always": it runs at the magnetometer rate only, and inlined into the step loop it
# slowed both plants by 0.6 us a step (docs/explanation/performance.md, hardware-rig)
@jit(nrt=False)
def motor_field_step(x, pp, field_out):
    """Magnetic field of the four motors' currents at the IMU modules (B, T), one magnetometer sample.

    Each motor's supply and phase leads run along its arm past the hub where the five modules sit
    (within 3 cm of each other, so all five see the same field and the ensemble of Sec. 4-1 cannot
    average it away). Motor ``i`` draws ``I_i = I_hover (f_i / f_hover)^1.5`` (momentum theory: the
    propeller's shaft power goes with thrust^1.5, at a fixed supply the current with the power;
    ``f_i`` the motor's true thrust, Eq. 40 and :func:`motor_thrust`); its leads' field at the hub
    is ``(I_i / I_hover) (B_steady + B_ripple w_i) d_i``, ``d_i`` horizontal and perpendicular to
    arm ``i`` and ``w_i`` standard normal per sample: the PWM and commutation ripple of the driver's
    current (kHz) aliased by the magnetometer's sampling, independent between motors. Magnitude:
    a lead pair 5 mm apart 4 cm from the modules carrying the hover current (about 3.2 A: the 6 A
    drivers of Sec. 4-1 at the 850 gr.F ceiling, scaled by (557.7 / 850)^1.5) gives
    ``mu0 I s / (2 pi r^2)`` = 2 uT of steady field (20 mG, 4 % of the site's 47 uT); the ripple is
    a fraction of that after the drivers' input capacitors (``hilms``: 0.32 uT, fitted to Table 6's
    two psi; the paper's equal psi bound the steady part near 0: docs/explanation/readings.md, "Table 6's
    yaw"). This is what ArduPilot's compass-motor calibration measures (field per amp of current).
    ``x`` is the rig state (motor voltages in ``x[13:17]``), ``pp`` the PhysicsParams; writes
    ``field_out`` (3,).
    """
    hw = pp.hw
    f_hover_inv = 4.0 / (pp.mass * pp.g)  # 1 / the hover thrust per motor, where the current is I_hover
    fx = 0.0
    fy = 0.0
    for i in range(4):
        f = motor_thrust(x[13 + i], i, pp.k_v, pp.f_ceiling, pp.thrust_efficiency[i], hw)
        if f > 0.0:
            r = f * f_hover_inv
            b = r * math.sqrt(r) * (hw.mag_steady + hw.mag_ripple * _normal(hw.rng))
            fx += b * _LEAD_FIELD_X[i]
            fy += b * _LEAD_FIELD_Y[i]
    field_out[0] = fx
    field_out[1] = fy
    field_out[2] = 0.0
