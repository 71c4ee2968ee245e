"""Equations of motion of the rig: Eq. 1 (virtual translation) and Eq. 3 (rotation on the joint).

``state_derivative`` fills ``dx`` with the time derivative of the 17-entry state
(docs/explanation/conventions.md) for the held motor voltage commands ``v_cmd``:

* Eq. 1: ``m r'' = [0, 0, -m g] + R_WB [-f_xB, -f_yB, -f_zB - sum F_i]``; the disturbance
  force enters as a world-frame wind force ``F_w = -R_WB f_B``.
* Eq. 3 / A1: ``I omega' = tau - omega x I omega - omega x Jr (0, 0, Omega_r) - T_B`` with
  ``tau = (l (F4 - F2), l (F1 - F3), M1 - M2 + M3 - M4)`` (A6), ``Omega_r = w1 - w2 + w3 - w4``
  and ``-T_B`` the shocks plus the extra masses' gravity torque.
* Quaternion kinematics ``q' = q (x) (0, omega_B) / 2``.
* Motor lag ``V' = (V_cmd - V) / tau_motor``.
* Motor faults: motor i produces ``thrust_efficiency[i]`` (1 healthy, 0 dead) of
  Eq. 40's thrust; its rotor speed and reaction moment follow the thrust it produces.
* Hardware effects (:mod:`rig_emulator.physics.hardware`): each motor's true
  thrust (:func:`~rig_emulator.physics.hardware.motor_thrust`), and joint friction, the
  centre of gravity's offset from the pivot and the random body torque added to Eq. 3's
  torques (none of them in the ideal plant).
"""

from rig_emulator._jit import jit
from rig_emulator.physics.disturbances import extra_mass_effects, shock_torque, wind_force
from rig_emulator.physics.hardware import cog_gravity_torque, joint_friction_torque, motor_thrust
from rig_emulator.physics.motors import rotor_speed
from rig_emulator.physics.rotation import quat_derivative, quat_to_rot


@jit(inline="always")  # into rk4_step, once (physics/integrator.py: the cost of a call with p)
def state_derivative(t, x, v_cmd, p, wind, gusts, shocks, extra, R, dx):
    """dx = f(t, x) for the rig; ``p`` is a PhysicsParams namedtuple, ``R`` a 3x3 work array."""
    q0 = x[6]
    q1 = x[7]
    q2 = x[8]
    q3 = x[9]
    quat_to_rot(q0, q1, q2, q3, R)
    wx = x[10]
    wy = x[11]
    wz = x[12]

    eff = p.thrust_efficiency  # 1 = healthy; a motor fault lowers it (sensors/faults.py)
    hw = p.hw
    f1 = motor_thrust(x[13], 0, p.k_v, p.f_ceiling, eff[0], hw)
    f2 = motor_thrust(x[14], 1, p.k_v, p.f_ceiling, eff[1], hw)
    f3 = motor_thrust(x[15], 2, p.k_v, p.f_ceiling, eff[2], hw)
    f4 = motor_thrust(x[16], 3, p.k_v, p.f_ceiling, eff[3], hw)
    u1 = f1 + f2 + f3 + f4
    u2 = p.arm_length * (f4 - f2)
    u3 = p.arm_length * (f1 - f3)
    u4 = p.km_over_kf * (f1 - f2 + f3 - f4)
    omega_r = rotor_speed(f1, p.kf) - rotor_speed(f2, p.kf) + rotor_speed(f3, p.kf) - rotor_speed(f4, p.kf)

    # Eq. 1: thrust along -z_B, so the world thrust is -u1 * (third column of R_WB)
    fwx, fwy, fwz = wind_force(t, wind, gusts)
    inv_m = 1.0 / p.mass
    dx[0] = x[3]
    dx[1] = x[4]
    dx[2] = x[5]
    dx[3] = (-u1 * R[0, 2] + fwx) * inv_m
    dx[4] = (-u1 * R[1, 2] + fwy) * inv_m
    dx[5] = (-u1 * R[2, 2] + fwz) * inv_m - p.g

    # Eq. 3 with disturbance torques
    dixx, diyy, dizz, gtx, gty, gtz = extra_mass_effects(extra, R, p.g)
    stx, sty = shock_torque(t, shocks)
    ixx = p.ixx + dixx
    iyy = p.iyy + diyy
    izz = p.izz + dizz
    jr = p.rotor_inertia * omega_r
    # omega x I omega and omega x (0, 0, Jr Omega_r)
    cx = wy * izz * wz - wz * iyy * wy + wy * jr
    cy = wz * ixx * wx - wx * izz * wz - wx * jr
    cz = wx * iyy * wy - wy * ixx * wx
    tx = u2 - cx + stx + gtx
    ty = u3 - cy + sty + gty
    tz = u4 - cz + gtz
    if hw.friction or hw.cog_on or hw.noise_on:  # the real rig's joint and body torques
        fx, fy, fz = joint_friction_torque(wx, wy, wz, hw)
        bx, by, bz = cog_gravity_torque(R, hw, p.g)
        nt = hw.noise_torque
        tx += fx + bx + nt[0]
        ty += fy + by + nt[1]
        tz += fz + bz + nt[2]
    dx[10] = tx / ixx
    dx[11] = ty / iyy
    dx[12] = tz / izz

    quat_derivative(q0, q1, q2, q3, wx, wy, wz, dx[6:10])

    if p.tau_motor > 0.0:
        inv_tau = 1.0 / p.tau_motor
        for i in range(4):
            dx[13 + i] = (v_cmd[i] - x[13 + i]) * inv_tau
    else:
        for i in range(4):
            dx[13 + i] = 0.0
