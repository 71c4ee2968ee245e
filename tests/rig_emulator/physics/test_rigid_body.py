"""Eq. 1 and Eq. 3: equilibria, torque signs (A6), gyroscopics, disturbances, RK4 accuracy."""

import math

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.control.thrust_direction import thrust_direction
from rig_emulator.physics import state as S
from rig_emulator.physics.integrator import rk4_step
from rig_emulator.physics.motors import voltage_for_thrust
from rig_emulator.physics.rigid_body import state_derivative
from rig_emulator.physics.rotation import euler_from_quat, quat_from_euler
from rig_emulator.simulation.params import disturbances, physics_params

CFG = load_config("hilms-ideal", overrides={"sim.ground": False})
PP = physics_params(CFG)
NO_DIST = disturbances(CFG)


def _state(euler=(0.0, 0.0, 0.0), thrusts=None, omega=(0.0, 0.0, 0.0)):
    x = np.zeros(S.SIZE)
    quat_from_euler(*euler, x[S.QUAT : S.QUAT + 4])
    x[S.OMEGA : S.OMEGA + 3] = omega
    if thrusts is None:
        thrusts = [PP.mass * PP.g / 4] * 4
    x[S.MOTOR_V : S.MOTOR_V + 4] = [voltage_for_thrust(f, PP.k_v, PP.v_max) for f in thrusts]
    return x


def _deriv(x, t=0.0, pp=PP, dist=NO_DIST):
    dx = np.zeros(S.SIZE)
    state_derivative(t, x, x[S.MOTOR_V : S.MOTOR_V + 4].copy(), pp, dist.wind, dist.gusts, dist.shocks, dist.extra, np.zeros((3, 3)), dx)
    return dx


def test_hover_is_an_equilibrium():
    dx = _deriv(_state())
    assert np.allclose(dx, 0.0, atol=1e-12)


def test_eq1_tilted_thrust_gives_eq33_accelerations():
    phi, theta, psi = 0.1, -0.2, 0.7
    u1 = PP.mass * PP.g * 1.1
    dx = _deriv(_state((phi, theta, psi), [u1 / 4] * 4))
    ux, uy, uz = thrust_direction(phi, theta, psi)
    assert np.allclose(dx[S.VEL : S.VEL + 3], [ux * u1 / PP.mass, uy * u1 / PP.mass, uz * u1 / PP.mass - PP.g], atol=1e-12)


def test_a6_torques_about_body_axes():
    h = PP.mass * PP.g / 4
    dx = _deriv(_state(thrusts=[h, h - 0.5, h, h + 0.5]))  # F4 > F2: u2 = l (F4 - F2) > 0
    assert dx[S.OMEGA] == pytest.approx(PP.arm_length * 1.0 / PP.ixx)
    dx = _deriv(_state(thrusts=[h + 0.5, h, h - 0.5, h]))  # F1 > F3: u3 > 0
    assert dx[S.OMEGA + 1] == pytest.approx(PP.arm_length * 1.0 / PP.iyy)
    dx = _deriv(_state(thrusts=[h + 0.2, h - 0.2, h + 0.2, h - 0.2]))  # u4 = c (F1 - F2 + F3 - F4)
    assert dx[S.OMEGA + 2] == pytest.approx(PP.km_over_kf * 0.8 / PP.izz, rel=1e-9)


def test_torque_free_rotation_conserves_momentum_and_energy():
    """Euler's equations (Eq. 3) with zero torque: |I w| and w.I w constant under RK4."""
    pp = PP._replace(rotor_inertia=0.0, tau_motor=0.0)
    x = _state(omega=(1.0, 0.3, 2.0), thrusts=[0.0] * 4)
    inertia = np.array([pp.ixx, pp.iyy, pp.izz])
    work, R = np.zeros((5, S.SIZE)), np.zeros((3, 3))

    def invariants():
        w = x[S.OMEGA : S.OMEGA + 3]
        return np.linalg.norm(inertia * w), float(w @ (inertia * w))

    h0, e0 = invariants()
    for k in range(5000):
        rk4_step(k * 1e-3, 1e-3, x, np.zeros(4), pp, NO_DIST.wind, NO_DIST.gusts, NO_DIST.shocks, NO_DIST.extra, work, R)
    h1, e1 = invariants()
    assert abs(h1 - h0) / h0 < 1e-9 and abs(e1 - e0) / e0 < 1e-9
    assert abs(np.linalg.norm(x[S.QUAT : S.QUAT + 4]) - 1.0) < 1e-12


def test_rotor_gyroscopic_term_couples_roll_rate_into_pitch():
    """-omega x Jr (0, 0, Omega_r): with Omega_r != 0 a roll rate produces a pitch acceleration."""
    h = PP.mass * PP.g / 4
    x = _state(thrusts=[h + 1.0, h, h + 1.0, h], omega=(0.5, 0.0, 0.0))
    dx = _deriv(x)
    omega_r = 2 * math.sqrt((h + 1.0) / PP.kf) - 2 * math.sqrt(h / PP.kf)
    # the yaw-torque imbalance only drives z; pitch sees -(-wx Jr Omega_r) / Iyy
    assert dx[S.OMEGA + 1] == pytest.approx(0.5 * PP.rotor_inertia * omega_r / PP.iyy, rel=1e-9)


def test_shock_on_arm_1_pitches_body_y_negative():
    cfg = load_config("hilms-ideal", overrides={"disturbance.shocks": [{"t": 1.0, "arm": 1, "torque": 2.0, "duration": 0.1}]})
    d = disturbances(cfg)
    assert _deriv(_state(), t=0.5, dist=d)[S.OMEGA + 1] == 0.0
    assert _deriv(_state(), t=1.05, dist=d)[S.OMEGA + 1] == pytest.approx(-2.0 / PP.iyy)
    assert _deriv(_state(), t=1.2, dist=d)[S.OMEGA + 1] == 0.0


def test_extra_mass_adds_inertia_and_gravity_torque():
    cfg = load_config("hilms-ideal", overrides={"disturbance.extra_masses": [{"arm": 2, "mass": 0.1, "distance": 0.33}]})
    d = disturbances(cfg)
    dx = _deriv(_state(), dist=d)
    # arm 2 is +y_B; gravity is +z_B at level: torque x = p_y m g
    expected = 0.33 * 0.1 * PP.g / (PP.ixx + 0.1 * 0.33**2)
    assert dx[S.OMEGA] == pytest.approx(expected, rel=1e-12)
    assert dx[S.OMEGA + 1] == 0.0


def test_wind_force_enters_eq1():
    cfg = load_config("hilms-ideal", overrides={"disturbance.wind_force": [1.0, -2.0, 0.5]})
    dx = _deriv(_state(), dist=disturbances(cfg))
    assert np.allclose(dx[S.VEL : S.VEL + 3], np.array([1.0, -2.0, 0.5]) / PP.mass, atol=1e-12)


def test_gust_is_one_minus_cosine():
    cfg = load_config("hilms-ideal", overrides={"disturbance.gusts": [{"t": 2.0, "duration": 2.0, "force": [2.0, 0.0, 0.0]}]})
    d = disturbances(cfg)
    assert _deriv(_state(), t=3.0, dist=d)[S.VEL] == pytest.approx(2.0 / PP.mass)
    assert _deriv(_state(), t=1.9, dist=d)[S.VEL] == 0.0


def test_motor_lag_is_first_order():
    pp = PP
    x = _state(thrusts=[0.0] * 4)
    v_cmd = np.full(4, 10.0)
    work, R = np.zeros((5, S.SIZE)), np.zeros((3, 3))
    for k in range(int(pp.tau_motor / 1e-3)):
        rk4_step(k * 1e-3, 1e-3, x, v_cmd, pp, NO_DIST.wind, NO_DIST.gusts, NO_DIST.shocks, NO_DIST.extra, work, R)
    assert x[S.MOTOR_V] == pytest.approx(10.0 * (1 - math.exp(-1)), rel=1e-6)


def test_rk4_attitude_matches_constant_rate_rotation():
    pp = PP._replace(rotor_inertia=0.0, tau_motor=0.0)
    x = _state(omega=(0.0, 0.0, -0.5), thrusts=[0.0] * 4)  # body z is down: -wz_B turns psi positive
    work, R = np.zeros((5, S.SIZE)), np.zeros((3, 3))
    for k in range(1000):
        rk4_step(k * 1e-3, 1e-3, x, np.zeros(4), pp, NO_DIST.wind, NO_DIST.gusts, NO_DIST.shocks, NO_DIST.extra, work, R)
    assert euler_from_quat(*x[S.QUAT : S.QUAT + 4])[2] == pytest.approx(0.5, abs=1e-12)


def test_motor_fault_scales_that_motors_thrust_torque_and_rotor_speed():
    """A weak motor: motor 1 at 60 % of its thrust lowers u1, pitches (u3 < 0) and unbalances yaw."""
    h = PP.mass * PP.g / 4
    x = _state()
    pp = PP._replace(thrust_efficiency=np.array([0.6, 1.0, 1.0, 1.0]))
    dx = _deriv(x, pp=pp)
    lost = 0.4 * h
    assert dx[S.VEL + 2] == pytest.approx(-lost / PP.mass, rel=1e-9)
    assert dx[S.OMEGA + 1] == pytest.approx(-PP.arm_length * lost / PP.iyy, rel=1e-9)
    assert dx[S.OMEGA + 2] == pytest.approx(-PP.km_over_kf * lost / PP.izz, rel=1e-9)
    dead = _deriv(x, pp=PP._replace(thrust_efficiency=np.array([1.0, 1.0, 0.0, 1.0])))
    assert dead[S.OMEGA + 1] == pytest.approx(PP.arm_length * h / PP.iyy, rel=1e-9)


def test_vehicle_with_stopped_motors_rests_on_the_ground():
    """On the virtual ground without thrust (disarmed, failsafe) no sliding on."""
    from rig_emulator.physics.integrator import apply_ground

    pp = physics_params(load_config("hilms-ideal"))
    x = _state()
    x[S.POS + 2] = -0.01
    x[S.VEL : S.VEL + 3] = [2.0, -1.0, -3.0]
    apply_ground(x, pp, 0.5, 0.5)  # hover thrust: frictionless ground, the vehicle slides
    assert x[S.POS + 2] == 0.0 and list(x[S.VEL : S.VEL + 3]) == [2.0, -1.0, 0.0]
    x[S.MOTOR_V : S.MOTOR_V + 4] = 0.0
    apply_ground(x, pp, 0.5, 0.5)
    assert list(x[S.VEL : S.VEL + 3]) == [0.0, 0.0, 0.0]


def test_the_hardware_rigs_ground_holds_a_vehicle_standing_on_it_at_any_thrust():
    """sim.ground_contact = "hold" (physics/ground.py): on the ground at hover thrust the vehicle keeps
    the place it had at the start of the step and loses its horizontal velocity; above the ground the
    rule does nothing."""
    from rig_emulator.physics.integrator import apply_ground

    pp = physics_params(load_config("hilms"))
    assert pp.ground_hold and not physics_params(load_config("hilms-ideal")).ground_hold
    x = _state()
    x[S.POS : S.POS + 3] = [0.3, -0.2, -0.01]
    x[S.VEL : S.VEL + 3] = [2.0, -1.0, -3.0]
    apply_ground(x, pp, 0.25, -0.15)
    assert list(x[S.POS : S.POS + 3]) == [0.25, -0.15, 0.0] and list(x[S.VEL : S.VEL + 3]) == [0.0, 0.0, 0.0]
