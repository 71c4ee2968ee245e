"""The numbers a controller plug-in exchanges with the step loop: one flat float64 array each way.

The layout is part of the public plug-in interface (docs/how-to/your-controller.md); names are
stable. A compiled plug-in indexes ``obs`` and ``out`` with these constants; a Python
plug-in reads the same numbers through named views (:class:`rig_emulator.controllers.Observation`).

``obs`` (what the onboard computer has at a control instant, SI, paper frames: world ENU,
body FRD, paper Euler angles; Sec. 4-1 and Eq. 1):

* ``O_T`` time (s), ``O_DT`` the plug-in's period (s), ``O_RESET`` 1.0 on the first call
  after arming (the controller must forget its state), ``O_MODE`` the guidance mode
  (0 position references, 1 attitude references, 2 body-rate references: an offboard
  body-rate set-point, ``O_REF`` + ``REF_ATT_RATE`` then holds body rates FRD);
* ``O_REF_THRUST``: the collective thrust (N) of an offboard attitude or body-rate set-point
  (NaN: none given, hover thrust m g meant; NaN in position mode);
* ``O_EULER`` (3) attitude, ``O_EULER_RATE`` (3) Euler rates, ``O_BODY_RATE`` (3) body
  rates: the complementary filter's estimate (or the truth with ``sensors.feedback = "ideal"``);
* ``O_POS``, ``O_VEL`` (3 each): the onboard virtual translation of Eq. 1 (or the truth);
* ``O_THRUST`` (4): the filtered load-cell thrusts (N; the motors' true thrusts when the
  sensor models are off);
* ``O_REF`` (20): the guidance reference, laid out as ``REF_*`` of
  :mod:`rig_emulator.control.controller` (position, velocity, acceleration, yaw, attitude,
  attitude rate, attitude acceleration);
* ``O_ATT_TARGET``, ``O_ATT_RATE_TARGET``, ``O_ATT_ACC_TARGET`` (3 each) and
  ``O_THRUST_TARGET``: for a plug-in that replaces the attitude loop only, what the rig's
  position loop asks of it (the shaped attitude reference and u1, N); NaN otherwise;
* ``O_TRUE`` (13: position, velocity, quaternion w x y z of R_WB, body rates) and
  ``O_TRUE_VALID``: the true state, only when the run flies on ideal feedback (else NaN, 0);
* ``O_IMU_RAW`` (``IMU_RAW_MAX`` = 8 modules x 9: gyro, accel, mag counts per module),
  ``O_N_IMU`` modules present, ``O_CELL_RAW`` (4) load-cell counts: raw samples, only for a
  plug-in that asks for them (else NaN);
* ``O_RIG`` onwards: the rig's constants (mass, gravity, inertia, arm length, km/kf, kf, N per
  V, supply voltage, motor thrust limit, tilt limit, reference-filter bandwidth);
* ``O_REF_ACC_FF``: 1.0 when an offboard acceleration set-point asks for the reference
  acceleration as a feed-forward (position mode), else 0;
* ``O_THRUST_CMD`` (4): the motor thrusts (N) the rig commanded at the previous control step,
  after the allocation's saturation (what the sliding-mode law's rotor gyroscopic term uses).

``out`` (what the plug-in decides): ``C_CMD`` (4) the command of its declared kind (below);
``C_ATT_DES`` (3) and ``C_ATT_RATE_DES`` (3) optionally the attitude it aims at (logs,
telemetry and the loss-of-control supervisor use it; NaN: not reported); ``C_SURFACE`` (3)
sliding surfaces, ``C_UXY`` (2) the virtual inputs uX, uY of Eq. 34 and ``C_FLAGS`` (the
allocation's ``SATURATED_*`` / ``TILT_CLAMPED`` bits as a float) for logs and telemetry,
optionally (NaN: not reported). The loop sets every ``out`` value to NaN before each call.

Command kinds: ``K_VOLTAGES`` four motor voltages (V), ``K_THRUSTS`` four motor thrusts (N),
``K_TORQUES`` (u1 N, u2, u3, u4 N m about the body axes FRD; the rig's allocation does the
rest, A6), ``K_ATTITUDE`` (u1 N, phi_d, theta_d, psi_d rad; the rig's reference filter and
attitude law do the rest).

Modes (what the controller replaces): ``P_BOTH`` both loops (the built-in strategies' kernel
too), ``P_ATTITUDE`` the attitude loop (the built-in position loop feeds it), ``P_POSITION``
the position loop (it commands ``K_ATTITUDE``), ``P_EXTERNAL`` no controller at all: the motor
voltages are set from outside between calls of the loop (lockstep). ``P_NONE`` is never flown
(every run has a controller, the built-in strategies' kernel being one, or takes its motor
commands from outside).
"""

# obs
O_T = 0
O_DT = 1
O_RESET = 2
O_MODE = 3
O_EULER = 4
O_EULER_RATE = 7
O_BODY_RATE = 10
O_POS = 13
O_VEL = 16
O_THRUST = 19
O_REF = 23  # the first O_REF_SIZE values of the guidance reference (REF_MODE .. REF_ATT_ACC)
O_REF_SIZE = 20  # (the offboard entries REF_THRUST, REF_ACC_FF that follow in ref are not passed on)
O_ATT_TARGET = 43
O_ATT_RATE_TARGET = 46
O_ATT_ACC_TARGET = 49
O_THRUST_TARGET = 52
O_TRUE_VALID = 53
O_TRUE = 54  # 13: pos (3), vel (3), quat (4), omega (3)
O_N_IMU = 67
O_IMU_RAW = 68  # IMU_RAW_MAX * 9
IMU_RAW_MAX = 8
O_CELL_RAW = 140  # 4
O_RIG = 144
O_MASS = 144
O_G = 145
O_IXX = 146
O_IYY = 147
O_IZZ = 148
O_ARM = 149
O_KM_KF = 150
O_KF = 151
O_K_V = 152
O_V_MAX = 153
O_F_MAX = 154
O_MAX_TILT = 155
O_REF_OMEGA = 156
O_REF_THRUST = 157  # the offboard collective thrust set-point u1 (N) in attitude/rate modes; NaN: hover (m g) or none
O_REF_ACC_FF = 158  # 1.0: an offboard acceleration set-point asks for REF_ACC as a feed-forward (else 0)
O_THRUST_CMD = 160  # 4: the motor thrusts (N) the rig commanded at the previous control step (after allocation)
OBS_SIZE = 164

# out
C_CMD = 0
C_ATT_DES = 4
C_ATT_RATE_DES = 7
C_SURFACE = 10  # 3: sliding surfaces s = e' + lambda e (logs and telemetry; NaN: none)
C_UXY = 13  # 2: the virtual inputs uX, uY of Eq. 34 (logs; NaN: none)
C_FLAGS = 15  # allocation and tilt-clamp flags the controller raised (an integer as a float; NaN: none)
OUT_SIZE = 16

# command kinds
K_VOLTAGES = 0
K_THRUSTS = 1
K_TORQUES = 2
K_ATTITUDE = 3

# modes
P_NONE = 0
P_BOTH = 1
P_ATTITUDE = 2
P_POSITION = 3
P_EXTERNAL = 4

# status (int64 array of STATUS_SIZE) written by the loop when a plug-in call fails
S_CODE = 0  # 0 ok, else ERR_*
S_STEP = 1  # physics step of the failing call
S_RETURN = 2  # the value the plug-in returned
STATUS_SIZE = 4
ERR_RETURNED = 1  # the plug-in returned non-zero (a Python plug-in raised, or a compiled one reported an error)
ERR_NONFINITE = 2  # a command was NaN or infinite
