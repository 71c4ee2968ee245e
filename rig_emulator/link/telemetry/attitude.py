"""Attitude and controller messages: one builder per message, ``(snapshot, ctx) -> message``.

Frames go through :mod:`protocol.frames`: MAVLink's attitude is ``R_NED_FRD = T_NED_ENU R_WB``;
body rates are FRD in both conventions.
"""

from __future__ import annotations

import math

from protocol.dialect import mavlink
from protocol.frames import (
    mavlink_euler_from_rwb_xyz,
    mavlink_quaternion_from_rwb_xyz,
    rwb_from_paper_euler,
    rwb_from_quaternion_xyz,
)
from rig_emulator.config.schema import STRATEGIES
from rig_emulator.link.telemetry import units as U
from rig_emulator.sensors.load_cell import GRF_N


def body_rates_from_paper_euler_rates(euler, euler_rates) -> tuple[float, float, float]:
    """omega_B (FRD) of paper Euler rates: the inverse of the Z-Y-X kinematics of Q = R_WB diag(1,-1,-1)."""
    phi, theta, _ = euler
    dphi, dtheta, dpsi = euler_rates
    p = dphi - math.sin(theta) * dpsi
    q_flu = math.cos(phi) * dtheta + math.sin(phi) * math.cos(theta) * dpsi
    r_flu = -math.sin(phi) * dtheta + math.cos(phi) * math.cos(theta) * dpsi
    return p, -q_flu, -r_flu


def thrust_fraction(u1_n: float, cfg) -> float:
    """Total thrust as a fraction of the four motors' ceiling (0..1)."""
    ceiling_n = 4.0 * cfg["motors.thrust_ceiling_grf"] * GRF_N
    return min(max(u1_n / ceiling_n, 0.0), 1.0) if math.isfinite(u1_n) else 0.0


def attitude(snap, ctx):
    roll, pitch, yaw = mavlink_euler_from_rwb_xyz(rwb_from_quaternion_xyz(*snap.quaternion))
    p, q, r = snap.body_rates  # FRD in both conventions (protocol.frames.mavlink_body_rates_from_omega_b)
    return mavlink.MAVLink_attitude_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), roll=roll, pitch=pitch, yaw=yaw,
        rollspeed=float(p), pitchspeed=float(q), yawspeed=float(r))


def attitude_quaternion(snap, ctx):
    w, x, y, z = mavlink_quaternion_from_rwb_xyz(rwb_from_quaternion_xyz(*snap.quaternion))
    p, q, r = snap.body_rates
    return mavlink.MAVLink_attitude_quaternion_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), q1=float(w), q2=float(x), q3=float(y), q4=float(z),
        rollspeed=float(p), pitchspeed=float(q), yawspeed=float(r), repr_offset_q=[0.0, 0.0, 0.0, 0.0])


def attitude_target(snap, ctx):
    # R from the Euler angles stays numpy's matmul (its rounding is BLAS's, not a fixed order of sums)
    q = mavlink_quaternion_from_rwb_xyz(tuple(rwb_from_paper_euler(*snap.euler_target).ravel().tolist()))
    p, qr, r = body_rates_from_paper_euler_rates(snap.euler_target, snap.euler_rate_target)
    return mavlink.MAVLink_attitude_target_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), type_mask=0, q=[float(v) for v in q],
        body_roll_rate=p, body_pitch_rate=qr, body_yaw_rate=r, thrust=thrust_fraction(snap.u[0], ctx.cfg))


def hilms_controller_state(snap, ctx):
    s = snap.sliding_surfaces
    phi_d, theta_d, psi_d = snap.euler_target
    return mavlink.MAVLink_hilms_controller_state_message(
        time_usec=U.time_usec(snap.stamp_us), strategy=STRATEGIES.index(ctx.cfg["control.strategy"]),
        s_phi=s[0], s_theta=s[1], s_psi=s[2], phi_des=phi_d, theta_des=theta_d, psi_des=psi_d,
        u1=snap.u[0], u2=snap.u[1], u3=snap.u[2], u4=snap.u[3], flags=snap.flags & 0xFF)
