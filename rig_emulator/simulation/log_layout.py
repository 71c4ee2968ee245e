"""Columns of the time series the step loop records (one row per log period)."""

T = 0
POS = 1  # 3: virtual position the controllers used, world ENU (m): the rig's own (Eq. 1 from its sensors) or the true one
VEL = 4  # 3: virtual velocity (m/s)
EULER = 7  # 3: phi, theta, psi the controllers used (estimated or true, rad)
OMEGA = 10  # 3: body rates omega_B (rad/s)
POS_DES = 13  # 3: desired position (NaN in attitude mode)
VEL_DES = 16  # 3
EULER_DES = 19  # 3: desired (filtered) attitude the attitude law tracks
THRUST = 22  # 4: motor thrusts from the motor state (N)
V_CMD = 26  # 4: motor voltage commands (V)
U = 30  # 4: u1 (N), u2, u3, u4 (N m) as allocated (A6)
S = 34  # 3: sliding surfaces
FLAGS = 37  # saturation / tilt-clamp flags
WAYPOINT = 38  # index of the waypoint being flown to
EULER_RATE = 39  # 3
EULER_RATE_DES = 42  # 3
MODE = 45  # 0 position, 1 attitude
UXY = 46  # 2: virtual inputs uX, uY (Eq. 34)
POS_TRUE = 48  # 3: physics position (POS is what the controllers were fed)
EULER_TRUE = 51  # 3: physics attitude (EULER is what the controllers were fed)
THRUST_MEAS = 54  # 4: filtered load-cell thrusts (N)
HEALTH = 58  # 2: rejected IMU modules mask, rejected load cells mask
FAILSAFE = 60  # latched failsafe cause (control/supervisor.py ALERT_* bits); 0 = not tripped
ESTIMATE_INVALID = 61  # fused IMU estimate invalid (supervisor INVALID_* bits: 1 gyro, 2 accel, 4 mag)
NCOLS = 62

NAMES = {
    "t": (T, 1),
    "pos": (POS, 3),
    "vel": (VEL, 3),
    "euler": (EULER, 3),
    "omega": (OMEGA, 3),
    "pos_des": (POS_DES, 3),
    "vel_des": (VEL_DES, 3),
    "euler_des": (EULER_DES, 3),
    "thrust": (THRUST, 4),
    "v_cmd": (V_CMD, 4),
    "u": (U, 4),
    "s": (S, 3),
    "flags": (FLAGS, 1),
    "waypoint": (WAYPOINT, 1),
    "euler_rate": (EULER_RATE, 3),
    "euler_rate_des": (EULER_RATE_DES, 3),
    "mode": (MODE, 1),
    "uxy": (UXY, 2),
    "pos_true": (POS_TRUE, 3),
    "euler_true": (EULER_TRUE, 3),
    "thrust_meas": (THRUST_MEAS, 4),
    "health": (HEALTH, 2),
    "failsafe": (FAILSAFE, 1),
    "estimate_invalid": (ESTIMATE_INVALID, 1),
}
