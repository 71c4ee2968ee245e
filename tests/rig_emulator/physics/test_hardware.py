"""The real rig's effects (physics/hardware.py): sign and size of each, neutral = ideal."""

import math

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.physics import state as S
from rig_emulator.physics.hardware import (actuator_chain, cog_gravity_torque, frame_vibration_step,
                                           joint_friction_torque, motor_field_step, motor_thrust,
                                           torque_noise_step)
from rig_emulator.physics.motors import GRAM_FORCE_N
from rig_emulator.physics.rotation import quat_from_euler, quat_to_rot
from rig_emulator.simulation.params import control_params, physics_params, smc_gains_si

IDEAL = load_config("hilms-ideal")


def _pp(**overrides):
    return physics_params(IDEAL.with_overrides(overrides))


def _rot(phi=0.0, theta=0.0, psi=0.0):
    q = np.zeros(4)
    quat_from_euler(phi, theta, psi, q)
    R = np.zeros((3, 3))
    quat_to_rot(q[0], q[1], q[2], q[3], R)
    return R


def test_the_ideal_plant_has_no_effect_switched_on():
    hw = physics_params(IDEAL).hw
    assert not (hw.friction or hw.cog_on or hw.act_on or hw.noise_on or hw.vib_on)
    assert hw.mag_ripple == 0.0 and hw.mag_steady == 0.0
    assert hw.curve_n == 1.0 and np.all(hw.gain == 1.0) and hw.bias == 0.0


def test_joint_friction_opposes_the_rate_viscous_plus_smoothed_coulomb():
    hw = _pp(**{"joint.viscous": [0.02, 0.03, 0.04], "joint.coulomb": [0.01, 0.01, 0.02],
                "joint.coulomb_smoothing": 0.05}).hw
    tx, ty, tz = joint_friction_torque(1.0, -2.0, 0.0, hw)
    assert tx == pytest.approx(-(0.02 + 0.01 * math.tanh(20.0)))
    assert ty == pytest.approx(0.06 + 0.01 * math.tanh(40.0))
    assert tz == 0.0
    # near zero rate the Coulomb step is smoothed: a tenth of the smoothing rate gives about a tenth
    tx, _, _ = joint_friction_torque(0.005, 0.0, 0.0, hw)
    assert tx == pytest.approx(-(0.02 * 0.005 + 0.01 * math.tanh(0.1)))
    assert joint_friction_torque(3.0, 3.0, 3.0, physics_params(IDEAL).hw) == (0.0, 0.0, 0.0)


def test_cog_forward_of_the_pivot_pitches_the_nose_down_with_m_g_x():
    pp = _pp(**{"joint.cog_offset": [0.005, 0.0, 0.0]})
    tx, ty, tz = cog_gravity_torque(_rot(), pp.hw, pp.g)
    # B is FRD: gravity along +z_B when level; r x f = (0, -x m g, 0): a torque that lowers the nose
    assert ty == pytest.approx(-0.005 * pp.mass * pp.g)
    assert tx == pytest.approx(0.0, abs=1e-15) and tz == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("z, restoring", [(0.004, True), (-0.004, False)])
def test_cog_below_the_joint_is_a_pendulum_above_it_an_inverted_one(z, restoring):
    pp = _pp(**{"joint.cog_offset": [0.0, 0.0, z]})
    phi = math.radians(10.0)
    tx, _, _ = cog_gravity_torque(_rot(phi=phi), pp.hw, pp.g)
    # size m g |z| sin(phi); a torque about x_B of the opposite sign to phi restores (x_B is the roll axis)
    assert abs(tx) == pytest.approx(pp.mass * pp.g * abs(z) * math.sin(phi), rel=1e-9)
    # positive phi is a positive rotation about x of the Euler (FLU) frame = x_B: restoring means tx < 0
    assert (tx < 0.0) == restoring


def test_motor_thrust_neutral_is_eq40_and_the_convex_curve_reaches_850_grf_at_15_v():
    pp = physics_params(IDEAL)
    for v in (0.0, 3.0, 11.7, 15.0):
        assert motor_thrust(v, 0, pp.k_v, pp.f_ceiling, 1.0, pp.hw) == min(pp.k_v * v, pp.f_ceiling)
    convex = _pp(**{"motors.curve_exponent": 1.70}).hw
    hover = pp.mass * pp.g / 4.0
    v_hover = hover / pp.k_v
    assert motor_thrust(v_hover, 0, pp.k_v, pp.f_ceiling, 1.0, convex) == pytest.approx(hover)
    f15 = motor_thrust(15.0, 0, pp.k_v, pp.f_ceiling, 1.0, convex) / GRAM_FORCE_N
    assert f15 == pytest.approx(850.0, rel=0.01)  # Eq. 40 alone gives 714 gr.F there
    assert motor_thrust(5.0, 0, pp.k_v, pp.f_ceiling, 1.0, convex) < pp.k_v * 5.0  # convex: below the line


def test_motor_gain_and_bias_scale_and_shift_the_thrust():
    pp = _pp(**{"motors.thrust_gain": [1.05, 0.95, 1.0, 1.0], "motors.thrust_bias_grf": 20.0})
    f = pp.k_v * 10.0 + 20.0 * GRAM_FORCE_N
    assert motor_thrust(10.0, 0, pp.k_v, pp.f_ceiling, 1.0, pp.hw) == pytest.approx(1.05 * f)
    assert motor_thrust(10.0, 1, pp.k_v, pp.f_ceiling, 1.0, pp.hw) == pytest.approx(0.95 * f)
    assert motor_thrust(0.0, 0, pp.k_v, pp.f_ceiling, 1.0, pp.hw) == 0.0  # a stopped motor has no bias
    assert motor_thrust(10.0, 0, pp.k_v, pp.f_ceiling, 0.0, pp.hw) == 0.0  # a dead motor (fault) none


def test_actuator_chain_delays_by_whole_steps_quantises_and_dead_bands():
    pp = _pp(**{"control.actuation_delay": 0.003, "motors.command_steps": 150, "motors.esc_deadband_v": 0.5})
    hw = pp.hw
    assert hw.delay_steps == 3 and hw.quantum == pytest.approx(0.1)
    out = []
    for k in range(8):
        cmd = np.full(4, 7.04 if k >= 2 else 0.3)
        out.append(actuator_chain(k, cmd, hw)[0])
    # 0.3 V is inside the dead-band -> 0; the step at k = 2 arrives at k = 5, quantised to 7.0 V
    assert out[:5] == [0.0] * 5
    assert out[5] == pytest.approx(7.0) and out[7] == pytest.approx(7.0)
    ideal = physics_params(IDEAL).hw
    cmd = np.array([1.0, 2.0, 3.0, 4.0])
    assert actuator_chain(0, cmd, ideal) is cmd


def _noise_series(seed, n=40000, hover=True, start=None):
    pp = physics_params(IDEAL.with_overrides({"disturbance.torque_noise": [0.05, 0.0, 0.01],
                                              "disturbance.torque_noise_corner_hz": 2.0,
                                              "sim.seed": seed}))
    x = np.zeros(S.SIZE)
    if hover:
        x[S.MOTOR_V : S.MOTOR_V + 4] = pp.mass * pp.g / 4.0 / pp.k_v
    if start is not None:
        pp.hw.noise_torque[:] = start
    out = np.zeros((n, 3))
    for i in range(n):
        torque_noise_step(x, pp)
        out[i] = pp.hw.noise_torque
    return out, pp.hw


def test_torque_noise_has_the_configured_std_at_hover_and_correlation_and_is_seeded():
    a, hw = _noise_series(4)
    assert a[:, 0].std() == pytest.approx(0.05, rel=0.2)
    assert a[:, 2].std() == pytest.approx(0.01, rel=0.2)
    assert np.all(a[:, 1] == 0.0)
    lag = a[1:, 0] @ a[:-1, 0] / (a[:, 0] @ a[:, 0])
    assert lag == pytest.approx(hw.noise_a, abs=0.01)  # first-order: one-step correlation exp(-2 pi fc dt)
    b, _ = _noise_series(4)
    c, _ = _noise_series(5)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_torque_noise_dies_out_with_the_filter_once_the_motors_stop():
    a, hw = _noise_series(4, n=2000, hover=False, start=[0.05, 0.0, 0.01])
    assert a[0, 0] == pytest.approx(0.05 * hw.noise_a)  # no new drive with the rotors stopped
    assert np.all(np.abs(a[-1]) < 1e-6)  # decays as a^k (2 Hz corner: 1 s = 12.6 time constants)


def test_frame_vibration_is_at_the_blade_pass_frequency_with_the_hover_amplitude():
    pp = _pp(**{"vibration.accel_amplitude": [0.0, 0.0, 1.0], "vibration.blades": 2})
    x = np.zeros(S.SIZE)
    x[S.MOTOR_V : S.MOTOR_V + 4] = pp.mass * pp.g / 4.0 / pp.k_v  # hover
    dt = 0.002
    vib = np.zeros(6)
    pp.hw.vib_phase[:] = 0.0  # four rotors in phase: amplitude 4
    z = []
    for _ in range(2000):
        frame_vibration_step(dt, x, pp, vib)
        z.append(vib[5])
    z = np.array(z)
    assert np.abs(z).max() == pytest.approx(4.0, rel=0.02)
    assert np.all(vib[:5] == 0.0)
    omega = math.sqrt(pp.mass * pp.g / 4.0 / pp.kf)
    f_blade = 2 * omega / (2 * math.pi)
    spec = np.abs(np.fft.rfft(z))
    freqs = np.fft.rfftfreq(z.size, dt)
    f_seen = freqs[np.argmax(spec)]
    f_alias = abs(f_blade - round(f_blade * dt) / dt)  # sampled at 500 Hz
    assert f_seen == pytest.approx(f_alias, abs=1.0)


def _field_series(thrust_per_motor_N, ripple_uT=0.0, steady_uT=0.0, n=20000, seed=3):
    pp = _pp(**{"motor_field.ripple_uT": ripple_uT, "motor_field.steady_uT": steady_uT, "sim.seed": seed})
    x = np.zeros(S.SIZE)
    x[S.MOTOR_V : S.MOTOR_V + 4] = np.asarray(thrust_per_motor_N, dtype=float) / pp.k_v  # Eq. 40, ideal curve
    out = np.zeros((n, 3))
    for i in range(n):
        motor_field_step(x, pp, out[i])
    return out, pp


def test_motor_field_ripple_has_the_hover_rms_per_motor_across_the_arms_and_is_seeded():
    hover = physics_params(IDEAL).mass * 9.81 / 4.0
    b, pp = _field_series([hover] * 4, ripple_uT=0.3)
    assert pp.hw.mag_ripple == pytest.approx(0.3e-6) and pp.hw.mag_steady == 0.0
    # two motors' leads on each horizontal body axis (arms along x give a field along y and back)
    assert b[:, 0].std() == pytest.approx(math.sqrt(2) * 0.3e-6, rel=0.03)
    assert b[:, 1].std() == pytest.approx(math.sqrt(2) * 0.3e-6, rel=0.03)
    assert np.all(b[:, 2] == 0.0) and abs(b[:, 0].mean()) < 0.05 * 0.3e-6
    lag = b[1:, 0] @ b[:-1, 0] / (b[:, 0] @ b[:, 0])
    assert abs(lag) < 0.03  # white: the driver's kHz ripple aliased by the sampling
    again, _ = _field_series([hover] * 4, ripple_uT=0.3)
    other, _ = _field_series([hover] * 4, ripple_uT=0.3, seed=4)
    assert np.array_equal(b, again) and not np.array_equal(b, other)


def test_motor_field_grows_with_the_current_as_thrust_to_the_1_5_and_vanishes_with_the_motors_off():
    hover = physics_params(IDEAL).mass * 9.81 / 4.0
    lo, _ = _field_series([hover] * 4, ripple_uT=0.3, n=8000)
    hi, _ = _field_series([1.2 * hover] * 4, ripple_uT=0.3, n=8000)  # under the 714 gr.F ceiling
    assert hi[:, 0].std() / lo[:, 0].std() == pytest.approx(1.2 ** 1.5, rel=0.04)
    off, _ = _field_series([0.0] * 4, ripple_uT=0.3, steady_uT=2.0, n=10)
    assert np.all(off == 0.0)


def test_motor_field_steady_part_cancels_between_opposite_arms_and_follows_a_differential():
    hover = physics_params(IDEAL).mass * 9.81 / 4.0
    even, _ = _field_series([hover] * 4, steady_uT=2.0, n=1)
    assert np.all(np.abs(even) < 1e-18)
    # pitch: motor 1 (arm +x) up, motor 3 (arm -x) down; their leads' fields lie along y
    d = 0.1 * hover
    pitch, _ = _field_series([hover + d, hover, hover - d, hover], steady_uT=2.0, n=1)
    expect = 2.0e-6 * ((1.1 ** 1.5) - (0.9 ** 1.5))
    assert pitch[0, 1] == pytest.approx(expect, rel=1e-9) and pitch[0, 0] == 0.0


def test_model_mismatch_and_readings_enter_the_controllers_only():
    cfg = IDEAL.with_overrides({"controller_model.inertia_scale": [1.2, 0.8, 1.0],
                                "controller_model.arm_length_scale": 0.9,
                                "controller_model.thrust_per_volt_scale": 1.1})
    cp, pp = control_params(cfg), physics_params(cfg)
    assert cp.ixx == pytest.approx(1.2 * pp.ixx) and cp.iyy == pytest.approx(0.8 * pp.iyy)
    assert cp.arm_length == pytest.approx(0.9 * pp.arm_length) and cp.k_v == pytest.approx(1.1 * pp.k_v)
    assert pp.ixx == IDEAL["airframe.ixx"]


@pytest.mark.parametrize("gain, lam, k_roll, lam_roll", [
    ("si", "si", 1.47, 0.17),
    ("thrust", "si", 1.47 * 0.28 / 0.062, 0.17),
    ("torque", "si", 1.47 / 0.062, 0.17),
    ("si", "deg", 1.47, 0.17 * 180 / math.pi),
    ("si", "time-constant", 1.47, 1 / 0.17),
])
def test_smc_gain_readings(gain, lam, k_roll, lam_roll):
    cfg = IDEAL.with_overrides({"smc.gain_reading": gain, "smc.lambda_reading": lam})
    k, lm = smc_gains_si(cfg, 0.062, 0.062, 0.116, 0.28, 0.016)
    assert k[0] == pytest.approx(k_roll) and lm[0] == pytest.approx(lam_roll)
    if gain == "thrust":
        assert k[2] == pytest.approx(1.42 * 0.016 / 0.116)  # yaw: the thrust difference acts through kM/kF (A6)
