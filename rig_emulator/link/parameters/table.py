"""The rig's parameters as MAVLink parameters: stable short names, REAL32 values.

The table is built from :data:`rig_emulator.config.schema.SCHEMA` in schema order: each
scalar float is one parameter, each vec3 (or fixed-length list) element one parameter,
each text choice (strategy, switching function, membership geometry) its index into the
choices, each bool 0/1. Every value is sent as MAV_PARAM_TYPE_REAL32 (MAVSDK and MAVProxy
decode integer types differently for a generic autopilot) in the schema's unit.

Names (at most 16 characters, unique; tested) are ``SHORT_NAMES[key]`` followed, for list
elements, by the key's element suffix (``_PHI``/``_THE``/``_PSI`` for attitude axes,
``_X``/``_Y``/``_Z`` for world axes, ``1``..``4`` for ``flc.r``). Examples:
``smc.k[0]`` -> ``SMC_K_PHI``, ``flc.d1_phi_deg`` -> ``FLC_D1_PHI`` (deg),
``guidance.switching_radius`` -> ``WP_RADIUS``, ``control.strategy`` -> ``CTL_STRATEGY``
(0 smc-flc, 1 flc, 2 smc, 3 pid, as HILMS_STRATEGY). ``rig-emulator params`` and
:func:`describe` list them all.

Keys in :data:`EXCLUDED` are not parameters of a running rig, for the reason given. A
schema key in neither table is not served (:func:`unmapped_keys`; a test keeps it empty).

After the schema's parameters come the read-only ones the rig derives (:data:`DERIVED`, each a
:class:`DerivedParam`): ``MPC_THR_HOVER``, PX4's hover throttle, the normalised collective
thrust (SET_ATTITUDE_TARGET.thrust) that carries the weight
(:class:`rig_emulator.headless.hover_thrust.HoverThrustEstimate`; docs/how-to/attitude-thrust.md).
A PARAM_SET of one is refused with the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rig_emulator.config.schema import SCHEMA, Spec

ATT = ("_PHI", "_THE", "_PSI")
XYZ = ("_X", "_Y", "_Z")

#: dotted schema key -> (short name, element suffixes or None)
SHORT_NAMES: dict[str, tuple[str, tuple | None]] = {
    "sim.physics_rate_hz": ("SIM_PHYS_HZ", None),
    "sim.control_rate_hz": ("SIM_CTRL_HZ", None),
    "sim.log_rate_hz": ("SIM_LOG_HZ", None),
    "sim.ground": ("SIM_GROUND", None),
    "sim.ground_contact": ("SIM_GND_CONTACT", None),
    "airframe.mass": ("AF_MASS", None),
    "airframe.ixx": ("AF_IXX", None),
    "airframe.iyy": ("AF_IYY", None),
    "airframe.izz": ("AF_IZZ", None),
    "airframe.arm_length": ("AF_ARM_LEN", None),
    "airframe.rotor_inertia": ("AF_ROTOR_J", None),
    "airframe.km_over_kf": ("AF_KM_KF", None),
    "airframe.gravity": ("AF_GRAVITY", None),
    "motors.thrust_per_volt_grf": ("MOT_GRF_PER_V", None),
    "motors.voltage_max": ("MOT_V_MAX", None),
    "motors.thrust_ceiling_grf": ("MOT_F_MAX_GRF", None),
    "motors.time_constant": ("MOT_TAU", None),
    "motors.kf": ("MOT_KF", None),
    "motors.kv_rpm_per_v": ("MOT_KV", None),
    "control.strategy": ("CTL_STRATEGY", None),
    "control.max_tilt_deg": ("CTL_MAX_TILT", None),
    "control.reference_time_constant": ("CTL_REF_TAU", None),
    "smc.k": ("SMC_K", ATT),
    "smc.lam": ("SMC_LAM", ATT),
    "smc.switching": ("SMC_SWITCHING", None),
    "smc.boundary_layer": ("SMC_BL", None),
    "smc.position_k": ("SMC_POS_K", XYZ),
    "smc.position_lam": ("SMC_POS_LAM", XYZ),
    "smc.position_boundary_layer": ("SMC_POS_BL", None),
    "flc.r": ("FLC_R", ("1", "2", "3", "4")),
    "flc.geometry": ("FLC_GEOMETRY", None),
    "flc.d1_phi_deg": ("FLC_D1_PHI", None),
    "flc.d1_theta_deg": ("FLC_D1_THE", None),
    "flc.d1_psi_deg": ("FLC_D1_PSI", None),
    "flc.d1_dphi_deg_s": ("FLC_D1_DPHI", None),
    "flc.d1_dtheta_deg_s": ("FLC_D1_DTHE", None),
    "flc.d1_dpsi_deg_s": ("FLC_D1_DPSI", None),
    "flc.d1_u2": ("FLC_D1_U2", None),
    "flc.d1_u3": ("FLC_D1_U3", None),
    "flc.d1_u4": ("FLC_D1_U4", None),
    "flc.d1_x": ("FLC_D1_X", None),
    "flc.d1_y": ("FLC_D1_Y", None),
    "flc.d1_z": ("FLC_D1_Z", None),
    "flc.d1_dx": ("FLC_D1_DX", None),
    "flc.d1_dy": ("FLC_D1_DY", None),
    "flc.d1_dz": ("FLC_D1_DZ", None),
    "flc.d1_u1": ("FLC_D1_U1", None),
    "flc.d1_ux": ("FLC_D1_UX", None),
    "flc.d1_uy": ("FLC_D1_UY", None),
    "pid.attitude_kp": ("PID_ATT_KP", ATT),
    "pid.attitude_ki": ("PID_ATT_KI", ATT),
    "pid.attitude_kd": ("PID_ATT_KD", ATT),
    "pid.position_kp": ("PID_POS_KP", XYZ),
    "pid.position_ki": ("PID_POS_KI", XYZ),
    "pid.position_kd": ("PID_POS_KD", XYZ),
    "pid.integral_limit": ("PID_I_LIMIT", None),
    "guidance.omega": ("GUI_OMEGA", None),
    "guidance.speed": ("MPC_XY_CRUISE", None),  # PX4: cruise speed of missions, RTL, goto (MAVSDK set/get_maximum_speed)
    "guidance.max_speed": ("MPC_XY_VEL_MAX", None),  # PX4: QGroundControl's change-speed slider range
    "guidance.switching_radius": ("WP_RADIUS", None),
    "guidance.min_leg_time": ("GUI_MIN_LEG_T", None),
    "guidance.takeoff_altitude": ("MIS_TAKEOFF_ALT", None),  # PX4's names: MAVSDK and QGroundControl use them
    "guidance.return_altitude": ("RTL_RETURN_ALT", None),
    "guidance.land_speed": ("MPC_LAND_SPEED", None),
    "mission.item0_home": ("MIS_ITEM0_HOME", None),
    "mission.max_leg_m": ("MIS_DIST_WPS", None),
    "fence.enabled": ("FENCE_ENABLE", None),
    "fence.action": ("FENCE_ACTION", None),
    "fence.radius": ("FENCE_RADIUS", None),
    "fence.alt_max": ("FENCE_ALT_MAX", None),
    "fence.alt_min": ("FENCE_ALT_MIN", None),
    "offboard.loss_timeout": ("COM_OF_LOSS_T", None),
    "offboard.loss_action": ("COM_OBL_ACT", None),
    "disturbance.wind_force": ("DIST_WIND", XYZ),
    "sensors.simulate": ("SENS_SIMULATE", None),
    "sensors.feedback": ("SENS_FEEDBACK", None),
    "sensors.calibration": ("SENS_CALIB", None),
    "estimation.ensemble": ("EST_ENSEMBLE", None),
    "estimation.load_cell_filter": ("EST_LC_FILTER", None),
    "estimation.tau_roll_pitch": ("EST_TAU_RP", None),
    "estimation.tau_yaw": ("EST_TAU_YAW", None),
    "estimation.accel_lowpass_hz": ("EST_ACC_LP_HZ", None),
    "estimation.iir_cutoff_hz": ("EST_IIR_HZ", None),
    "estimation.divergence_warning_m": ("EST_DIV_WARN", None),
    "health.update_rate_hz": ("HLT_RATE_HZ", None),
    "health.reject_window": ("HLT_REJ_WIN", None),
    "health.accel_tolerance": ("HLT_ACC_TOL", None),
    "health.mag_tolerance": ("HLT_MAG_TOL", None),
    "failsafe.enabled": ("FS_ENABLE", None),
    "failsafe.action": ("FS_ACTION", None),
    "failsafe.attitude_error_deg": ("FS_ATT_ERR", None),
    "failsafe.rate_limit_deg_s": ("FS_RATE", None),
    "failsafe.hold_time": ("FS_HOLD_T", None),
    "failsafe.on_estimate_invalid": ("FS_ON_EST", None),
    "failsafe.gcs_timeout": ("COM_DL_LOSS_T", None),
    "failsafe.gcs_action": ("NAV_DLL_ACT", None),
    "prearm.max_tilt_deg": ("ARM_MAX_TILT", None),
    "prearm.max_rate_deg_s": ("ARM_MAX_RATE", None),
    # the hardware rig's effects and readings (rig_emulator/physics/hardware.py)
    "motors.thrust_gain": ("MOT_GAIN", ("1", "2", "3", "4")),
    "motors.thrust_bias_grf": ("MOT_BIAS_GRF", None),
    "motors.curve_exponent": ("MOT_CURVE_N", None),
    "motors.curve_pivot_grf": ("MOT_CURVE_PV", None),
    "motors.command_steps": ("MOT_CMD_STEPS", None),
    "motors.esc_deadband_v": ("MOT_DEADBAND", None),
    "motors.thrust_loop_time_constant": ("MOT_TLOOP_T", None),
    "motors.thrust_loop_limit_grf": ("MOT_TLOOP_LIM", None),
    "control.actuation_delay": ("CTL_DELAY", None),
    "control.allocation_priority": ("CTL_ALLOC_PRIO", None),
    "controller_model.inertia_scale": ("MDL_I", ATT),
    "controller_model.arm_length_scale": ("MDL_ARM", None),
    "controller_model.thrust_per_volt_scale": ("MDL_KV", None),
    "smc.gain_reading": ("SMC_K_READ", None),
    "smc.lambda_reading": ("SMC_LAM_READ", None),
    "flc.position_rate_share": ("FLC_RATE_SHR", None),
    "disturbance.torque_noise": ("DST_TQ_NSE", XYZ),
    "disturbance.torque_noise_corner_hz": ("DST_TQ_FC", None),
    "joint.viscous": ("JNT_VISC", XYZ),
    "joint.coulomb": ("JNT_COUL", XYZ),
    "joint.coulomb_smoothing": ("JNT_COUL_W", None),
    "joint.cog_offset": ("JNT_COG", XYZ),
    "vibration.gyro_amplitude": ("VIB_GYRO", XYZ),
    "vibration.accel_amplitude": ("VIB_ACC", XYZ),
    "vibration.blades": ("VIB_BLADES", None),
    "motor_field.ripple_uT": ("MAGM_RIPPLE", None),
    "motor_field.steady_uT": ("MAGM_STEADY", None),
}

#: schema keys that are not parameters of a running rig, and why
EXCLUDED: dict[str, str] = {
    "controller.plugin": "text, a plug-in name; fixed at start (serve --controller)",
    "controller.params": "the plug-in's own parameters are served under the prefix it declares",
    "controller.call": "how a compiled plug-in runs; fixed at start",
    "sim.duration": "the serve run's length is --duration",
    "sim.seed": "an integer beyond REAL32 precision; fixed at start",
    "airframe.name": "text, a preset name",
    "guidance.type": "chosen by flight modes and set-point commands",
    "guidance.hover_position": "set by position-target commands and modes",
    "guidance.yaw_deg": "set by position/attitude-target commands",
    "guidance.amplitude_deg": "harmonic guidance is a scenario chosen at start",
    "guidance.waypoints": "a list; the mission protocol carries waypoints",
    "initial.position": "initial state only",
    "initial.euler_deg": "initial state only",
    "disturbance.gusts": "a list of tables; fixed at start",
    "disturbance.shocks": "injected with MAV_CMD_HILMS_SHOCK",
    "disturbance.extra_masses": "injected with MAV_CMD_HILMS_EXTRA_MASS",
    "sensors.calibration_file": "text, a file path",
    "faults.events": "a list of timed fault events; fixed at start",
    "sensor_models.mpu6050": "a datasheet table; fixed at start",
    "sensor_models.hmc5883l": "a datasheet table; fixed at start",
    "sensor_models.imu_array": "a datasheet table; fixed at start",
    "sensor_models.zemic_l6d": "a datasheet table; fixed at start",
    "sensor_models.estimation": "a datasheet table; fixed at start",
}


@dataclass(frozen=True)
class Param:
    """One MAVLink parameter: ``key`` (and ``element`` for list entries) of the schema."""

    index: int
    name: str
    key: str
    element: int | None
    spec: Spec

    def value(self, cfg) -> float:
        """The current value as the float the wire carries."""
        v = cfg[self.key]
        if self.element is not None:
            v = v[self.element]
        if self.spec.kind == "str":
            return float(self.spec.choices.index(v))
        return float(v)

    def to_config(self, value: float, cfg):
        """The config value for a wire value; raises ValueError with a reason when unusable."""
        if not math.isfinite(value):
            raise ValueError(f"{self.name}: {value} is not a finite number")
        if self.spec.kind == "str":
            n = len(self.spec.choices)
            if value != int(value) or not 0 <= value < n:
                options = ", ".join(f"{i} {c}" for i, c in enumerate(self.spec.choices))
                raise ValueError(f"{self.name}: {value:g} must be an index 0..{n - 1} ({options})")
            return self.spec.choices[int(value)]
        if self.spec.kind == "bool":
            if value not in (0.0, 1.0):
                raise ValueError(f"{self.name}: {value:g} must be 0 or 1")
            return bool(value)
        if self.element is not None:
            values = list(cfg[self.key])
            values[self.element] = value
            return values
        return value

    @property
    def unit(self) -> str:
        return self.spec.unit


def _nominal_hover_fraction(cfg) -> float:
    """m g / u1_max with the controllers' Eq. 40 (what hovers when the motors follow Eq. 40)."""
    from rig_emulator.physics.motors import GRAM_FORCE_N

    k_v = cfg["motors.thrust_per_volt_grf"] * GRAM_FORCE_N * cfg["controller_model.thrust_per_volt_scale"]
    f_max = min(cfg["motors.thrust_ceiling_grf"] * GRAM_FORCE_N, k_v * cfg["motors.voltage_max"])
    return min(1.0, cfg["airframe.mass"] * cfg["airframe.gravity"] / (4.0 * f_max))


def _hover_fraction(server) -> float:
    return server.hover_thrust.value(server.rig)


@dataclass(frozen=True)
class DerivedParam:
    """A read-only parameter the served rig derives (no config key): ``live(server)`` is its value
    on a running :class:`~rig_emulator.link.server.RigServer`, ``nominal(cfg)`` the value a
    configuration implies before it runs (the parameter metadata's default and a listing's value)."""

    index: int
    name: str
    key: str  # a name for listings, not a config key
    spec: Spec
    live: object
    nominal: object
    element = None
    read_only = True

    def value(self, cfg) -> float:
        return float(self.nominal(cfg))

    def value_of(self, rig, server=None) -> float:
        """The value a ground station reads from the running ``rig`` served by ``server``."""
        return float(self.live(server)) if hasattr(server, "hover_thrust") else self.value(rig.cfg)

    def to_config(self, value: float, cfg):
        raise ValueError(f"{self.name} is read-only: the rig derives it ({self.spec.doc.split(';')[0]})")

    @property
    def unit(self) -> str:
        return self.spec.unit


#: name -> (listing key, spec, live value of a RigServer, nominal value of a config)
DERIVED: dict[str, tuple] = {
    "MPC_THR_HOVER": ("derived.hover_thrust",
                      Spec("float", "hover thrust: the normalised collective thrust (SET_ATTITUDE_TARGET.thrust, "
                                    "0..1 of the four motors' largest) that carries the weight (PX4's hover "
                                    "throttle); read-only, learnt in steady position-controlled flight, before "
                                    "that derived from the thrust chain (docs/how-to/attitude-thrust.md)",
                           "", 0.0, 1.0),
                      _hover_fraction, _nominal_hover_fraction),
}


def unmapped_keys() -> list[str]:
    """Schema keys neither named nor excluded: not served until added to SHORT_NAMES or EXCLUDED."""
    return [k for k in SCHEMA if k not in SHORT_NAMES and k not in EXCLUDED]


def build_table() -> list[Param]:
    """Every named parameter, in schema order."""
    table = []
    for key, spec in SCHEMA.items():
        if key not in SHORT_NAMES:
            continue
        base, suffixes = SHORT_NAMES[key]
        if suffixes is None:
            table.append(Param(len(table), base, key, None, spec))
        else:
            for i, suffix in enumerate(suffixes):
                table.append(Param(len(table), base + suffix, key, i, spec))
    for name, (key, spec, live, nominal) in DERIVED.items():
        table.append(DerivedParam(len(table), name, key, spec, live, nominal))
    return table


class ParamTable:
    """Lookup by index and by name. With a ``controller`` (a plug-in flying the rig) its own
    parameters follow the rig's (:mod:`rig_emulator.link.parameters.plugin_params`)."""

    def __init__(self, controller=None, source=None):
        """``source``: what has the controller now (``source.controller``; a LiveRig, whose
        reboot builds a new controller object); default: ``controller`` itself."""
        self.params = build_table()
        self.by_name = {p.name: p for p in self.params}
        if controller is not None:
            from rig_emulator.link.parameters.plugin_params import plugin_params

            extra = plugin_params(controller, len(self.params), set(self.by_name), source)
            self.params = self.params + extra
            self.by_name.update((p.name, p) for p in extra)
        self.controller = controller

    def __len__(self) -> int:
        return len(self.params)

    def lookup(self, name: str | None, index: int) -> Param | None:
        """PARAM_REQUEST_READ rules: index >= 0 wins, else the name."""
        if index >= 0:
            return self.params[index] if index < len(self.params) else None
        return self.by_name.get(name or "")


def describe(table: ParamTable | None = None) -> str:
    """A text listing: name, dotted key (element), unit."""
    table = table or ParamTable()
    lines = []
    for p in table.params:
        key = p.key if p.element is None else f"{p.key}[{p.element}]"
        if hasattr(p, "param"):  # a plug-in's parameter
            key = f"{p.key}.{p.param}" + ("" if p.element is None else f"[{p.element}]")
        lines.append(f"{p.index:3d} {p.name:16s} {key} [{p.unit}]" if p.unit else f"{p.index:3d} {p.name:16s} {key}")
    return "\n".join(lines)


def as_float32(value: float) -> float:
    """The value a REAL32 parameter carries (what the ground station will see)."""
    return float(np.float32(value))
