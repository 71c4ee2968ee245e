"""What a Python controller plug-in sees: named read-only views on the loop's observation array.

The numbers are those of :mod:`rig_emulator.control.plugin_layout` (SI, world ENU, body FRD,
paper Euler angles). The views are created once and the loop rewrites the numbers in
place before every call: copy what you want to keep (``obs.position.copy()``).
"""

from __future__ import annotations

import numpy as np

from rig_emulator.control import plugin_layout as PL
from rig_emulator.control.controller import (
    REF_ACC,
    REF_ATT,
    REF_ATT_ACC,
    REF_ATT_RATE,
    REF_POS,
    REF_VEL,
    REF_YAW,
)


class Reference:
    """The guidance reference (Sec. 4-4, Eq. 44): position mode or attitude mode."""

    def __init__(self, a: np.ndarray):
        r = a[PL.O_REF:]
        self._a = a
        self._mv = memoryview(a)  # indexing it gives Python floats, faster than numpy scalars
        self.position = r[REF_POS:REF_POS + 3]
        self.velocity = r[REF_VEL:REF_VEL + 3]
        self.acceleration = r[REF_ACC:REF_ACC + 3]
        self.attitude = r[REF_ATT:REF_ATT + 3]
        self.attitude_rate = r[REF_ATT_RATE:REF_ATT_RATE + 3]
        self.attitude_acc = r[REF_ATT_ACC:REF_ATT_ACC + 3]
        self._yaw = PL.O_REF + REF_YAW

    @property
    def yaw(self) -> float:
        """Desired yaw psi (rad), position mode."""
        return self._mv[self._yaw]

    @property
    def thrust(self) -> float:
        """Collective thrust u1 (N) of an offboard attitude or body-rate set-point; NaN when none
        was given (hover thrust m g meant) and in position mode."""
        return self._mv[PL.O_REF_THRUST]

    @property
    def acceleration_feedforward(self) -> bool:
        """True when an offboard acceleration set-point asks for ``acceleration`` as a feed-forward."""
        return self._mv[PL.O_REF_ACC_FF] != 0.0

    @property
    def body_rates(self) -> bool:
        """True for an offboard body-rate set-point: ``attitude_rate`` then holds body rates
        (FRD, rad/s) and ``attitude`` is not controlled."""
        return self._mv[PL.O_MODE] == 2.0


class Observation:
    """The onboard computer's view at a control instant (see the module docstring).

    Attributes (numpy views, (3,) unless noted): ``euler``, ``euler_rates``, ``body_rates``
    (estimates: complementary filter; the truth on ideal feedback), ``position``,
    ``velocity`` (onboard Eq. 1), ``thrusts`` (4, filtered load cells, N), ``thrust_commands``
    (4, the motor thrusts commanded at the previous control step, N), ``reference``
    (:class:`Reference`), ``attitude_target``, ``attitude_rate_target``,
    ``attitude_acc_target``, ``thrust_target`` (from the rig's position loop, for an
    attitude-only controller), ``true_position``, ``true_velocity``, ``true_quaternion`` (4),
    ``true_body_rates`` (ideal feedback only, else NaN: ``has_truth``), ``imu_raw`` (modules x
    9 counts) and ``cell_raw`` (4 counts) when the controller asked for raw samples; the rig's
    constants ``mass``, ``gravity``, ``inertia`` (3), ``arm_length``, ``km_over_kf``, ``kf``,
    ``thrust_per_volt``, ``voltage_max``, ``thrust_max``, ``max_tilt``, ``ref_omega``;
    ``array`` the whole flat array.

    The rig's constants are plain attributes (read from the array when the observation is
    built and again by :meth:`refresh` when the rig's parameters change); the per-step
    numbers are read from the array at each access.
    """

    def __init__(self, array: np.ndarray, n_imu: int = 5):
        a = array
        self.array = a
        self._mv = memoryview(a)
        self.euler = a[PL.O_EULER:PL.O_EULER + 3]
        self.euler_rates = a[PL.O_EULER_RATE:PL.O_EULER_RATE + 3]
        self.body_rates = a[PL.O_BODY_RATE:PL.O_BODY_RATE + 3]
        self.position = a[PL.O_POS:PL.O_POS + 3]
        self.velocity = a[PL.O_VEL:PL.O_VEL + 3]
        self.thrusts = a[PL.O_THRUST:PL.O_THRUST + 4]
        self.thrust_commands = a[PL.O_THRUST_CMD:PL.O_THRUST_CMD + 4]
        self.reference = Reference(a)
        self.attitude_target = a[PL.O_ATT_TARGET:PL.O_ATT_TARGET + 3]
        self.attitude_rate_target = a[PL.O_ATT_RATE_TARGET:PL.O_ATT_RATE_TARGET + 3]
        self.attitude_acc_target = a[PL.O_ATT_ACC_TARGET:PL.O_ATT_ACC_TARGET + 3]
        self.true_position = a[PL.O_TRUE:PL.O_TRUE + 3]
        self.true_velocity = a[PL.O_TRUE + 3:PL.O_TRUE + 6]
        self.true_quaternion = a[PL.O_TRUE + 6:PL.O_TRUE + 10]
        self.true_body_rates = a[PL.O_TRUE + 10:PL.O_TRUE + 13]
        self.imu_raw = a[PL.O_IMU_RAW:PL.O_IMU_RAW + 9 * n_imu].reshape(n_imu, 9)
        self.cell_raw = a[PL.O_CELL_RAW:PL.O_CELL_RAW + 4]
        self.inertia = a[PL.O_IXX:PL.O_IXX + 3]
        for name in ("euler", "euler_rates", "body_rates", "position", "velocity", "thrusts", "thrust_commands",
                     "attitude_target",
                     "attitude_rate_target", "attitude_acc_target", "true_position", "true_velocity",
                     "true_quaternion", "true_body_rates", "imu_raw", "cell_raw", "inertia"):
            getattr(self, name).flags.writeable = False
        for k, v in vars(self.reference).items():
            if isinstance(v, np.ndarray) and k != "_a":  # the views only: the loop writes the array itself
                v.flags.writeable = False
        self.refresh()

    def refresh(self) -> None:
        """Read the rig's constants from the array again (after a parameter change of the rig)."""
        for name, i in _CONSTANTS.items():
            self.__dict__[name] = float(self.array[i])

    t = property(lambda self: self._mv[PL.O_T], doc="time (s)")
    dt = property(lambda self: self._mv[PL.O_DT], doc="the controller's period (s)")
    reset = property(lambda self: self._mv[PL.O_RESET] != 0.0, doc="first call after arming")
    attitude_mode = property(lambda self: self._mv[PL.O_MODE] != 0.0, doc="guidance gives attitude references")
    thrust_target = property(lambda self: self._mv[PL.O_THRUST_TARGET], doc="u1 from the rig's position loop (N)")
    has_truth = property(lambda self: self._mv[PL.O_TRUE_VALID] != 0.0, doc="true state present (ideal feedback)")


#: the rig's constants: attribute -> index (thrust_per_volt: N per V, Eq. 40; thrust_max per motor, N;
#: max_tilt: control.max_tilt_deg in rad; ref_omega: the reference filter's bandwidth 1/tau, rad/s)
_CONSTANTS = {"mass": PL.O_MASS, "gravity": PL.O_G, "arm_length": PL.O_ARM, "km_over_kf": PL.O_KM_KF, "kf": PL.O_KF,
              "thrust_per_volt": PL.O_K_V, "voltage_max": PL.O_V_MAX, "thrust_max": PL.O_F_MAX,
              "max_tilt": PL.O_MAX_TILT, "ref_omega": PL.O_REF_OMEGA}
