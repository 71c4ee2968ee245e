"""Every tunable of the rig: name, kind, allowed range, unit and meaning.

The schema is the single source of truth for what a parameter file may contain. The
TOML presets under ``rig_emulator/presets/`` give values; :mod:`rig_emulator.config.loader`
checks each value against its :class:`Spec` and names the key and the allowed range when
one is out of bounds. Keys are dotted paths into the nested TOML tables.

Non-SI paper values keep their unit in the key (``d1_phi_deg``); the loader's
:func:`~rig_emulator.config.loader.to_si` converts them once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Spec:
    """One parameter: ``kind`` is float, int, str, bool, vec3, floats, table_list, tree or params (name -> numbers)."""

    kind: str
    doc: str
    unit: str = ""
    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    choices: tuple = ()
    length: int | None = None
    item: dict[str, "Spec"] = field(default_factory=dict)
    values: str = ""  # what a free-form value may be, in words (strings without choices, special lists)
    # a number's refused hole inside [lo, hi]: values strictly between ``lo`` and ``gap_to`` are refused
    # (``lo`` itself means "off", in the words of ``off``); None: no hole
    gap_to: float | None = None
    off: str = ""

    def describe_range(self) -> str:
        """The allowed interval of a number (or the choices of a string), as error messages quote it."""
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        lo = "(" if self.lo_open else "["
        return f"in {lo}{self._bound(self.lo)}, {self._bound(self.hi)}]"

    def in_gap(self, value: float) -> bool:
        """Whether ``value`` falls in the refused hole between ``lo`` (off) and ``gap_to``."""
        return self.gap_to is not None and self.lo < value < self.gap_to

    def describe_gap(self) -> str:
        """The values allowed around the hole (``0 (open loop) or in [1, 10000]``)."""
        return f"{self._bound(self.lo)} ({self.off}) or in [{self._bound(self.gap_to)}, {self._bound(self.hi)}]"

    def _bound(self, v: float) -> str:
        return str(int(v)) if self.kind == "int" and math.isfinite(v) else f"{v:g}"

    def describe_values(self) -> str:
        """What a value of this parameter may be, in words, for listings (``rig-emulator params``)."""
        if self.values:
            return self.values
        if self.choices:
            return self.describe_range()
        if self.kind == "bool":
            return "true or false"
        if self.kind == "str":
            return "any text"
        if self.kind == "tree":
            return "a table of overrides"
        if self.kind == "params":
            return "a table of name = number or list of numbers"
        if self.kind == "table_list":
            return "a list of tables, each with the fields below"
        number = "any finite number" if math.isinf(self.lo) and math.isinf(self.hi) else self.describe_range()
        if self.gap_to is not None:
            number = self.describe_gap()
        if self.kind == "int":
            return "an integer " + number if number.startswith("in ") else "any integer"
        if self.kind in ("vec3", "floats"):
            count = f"{self.length} " if self.length else "a list of "
            return (f"{count}finite numbers" if number == "any finite number" else f"{count}numbers, each {number}")
        return number


def F(doc, unit="", lo=-math.inf, hi=math.inf, lo_open=False, gap_to=None, off=""):
    return Spec("float", doc, unit, lo, hi, lo_open, gap_to=gap_to, off=off)


def I(doc, lo=-math.inf, hi=math.inf):  # noqa: E743 - short constructor names keep the table readable
    return Spec("int", doc, "", lo, hi)


def S(doc, choices):
    return Spec("str", doc, choices=tuple(choices))


def V3(doc, unit="", lo=-math.inf, hi=math.inf):
    return Spec("vec3", doc, unit, lo, hi, length=3)


def FS(doc, unit="", lo=-math.inf, hi=math.inf, length=None):
    return Spec("floats", doc, unit, lo, hi, length=length)


STRATEGIES = ("smc-flc", "flc", "smc", "pid")
GUIDANCE_TYPES = ("hover", "attitude", "helix", "waypoints", "sysid")
FENCE_ACTIONS = ("none", "warning", "hold", "return", "terminate", "land")  # PX4 GF_ACTION order
OFFBOARD_LOSS_ACTIONS = ("land", "hold", "return", "terminate")  # PX4 COM_OBL_ACT order

SCHEMA: dict[str, Spec] = {
    # --- simulation ----------------------------------------------------------------
    "sim.physics_rate_hz": F("physics (RK4) rate", "Hz", 50, 100_000),
    "sim.control_rate_hz": F("controller rate; an integer divisor of the physics rate", "Hz", 10, 100_000),
    "sim.log_rate_hz": F("rate of the recorded time series; an integer divisor of the physics rate", "Hz", 1, 100_000),
    "sim.duration": F("simulated time", "s", 0.0, 1e6, lo_open=True),
    "sim.seed": I("random seed (sensor noise, turn-on errors, gusts)", 0, 2**63 - 1),
    "sim.ground": Spec("bool", "virtual ground at Z = 0: the virtual position cannot go below it"),
    "sim.ground_contact": S("what the virtual ground does to a vehicle standing on it (physics/ground.py): "
                            "'hold' it keeps its place until its thrust lifts it (resting contact, the "
                            "hardware rig), 'frictionless' a tilted thrust slides it (the ideal plant)",
                            ("frictionless", "hold")),
    # --- airframe (Table 2) ------------------------------------------------------------
    "airframe.name": Spec("str", "airframe preset name", values="an airframe preset (chosen with --airframe)"),
    "airframe.mass": F("mass m (Table 2)", "kg", 0.0, 100.0, lo_open=True),
    "airframe.ixx": F("inertia Ixx (Table 2)", "kg m^2", 0.0, 100.0, lo_open=True),
    "airframe.iyy": F("inertia Iyy (Table 2)", "kg m^2", 0.0, 100.0, lo_open=True),
    "airframe.izz": F("inertia Izz (Table 2)", "kg m^2", 0.0, 100.0, lo_open=True),
    "airframe.arm_length": F("arm length l (Table 2)", "m", 0.0, 10.0, lo_open=True),
    "airframe.rotor_inertia": F("rotor inertia Jr about its axis (Eq. 3)", "kg m^2", 0.0, 1.0),
    "airframe.km_over_kf": F("reaction moment per thrust kM/kF (Eq. 38-39)", "m", 0.0, 1.0, lo_open=True),
    "airframe.gravity": F("gravitational acceleration g", "m/s^2", 0.0, 100.0, lo_open=True),
    # --- motors (Eq. 40) ---------------------------------------------------------------
    "motors.thrust_per_volt_grf": F("thrust per volt, Eq. 40 (F = 47.62 V gr.F)", "gr.F/V", 0.0, 1e4, lo_open=True),
    "motors.voltage_max": F("supply voltage ceiling (Fig. 11)", "V", 0.0, 100.0, lo_open=True),
    "motors.thrust_ceiling_grf": F("thrust ceiling per motor (Sec. 3-2)", "gr.F", 0.0, 1e5, lo_open=True),
    "motors.time_constant": F("first-order lag from voltage command to thrust", "s", 0.0, 10.0),
    "motors.kf": F("rotor thrust coefficient kF, F = kF Omega^2 (Eq. 38)", "N s^2/rad^2", 0.0, 1.0, lo_open=True),
    # hardware effects of the motor chain (physics/hardware.py; neutral values = the ideal plant)
    "motors.thrust_gain": FS("true thrust / Eq. 40 thrust per motor 1..4 (motor and propeller mismatch times "
                             "the common thrust-chain gain); 1 = Eq. 40", "", 0.5, 1.5, 4),
    "motors.thrust_bias_grf": F("common additive thrust bias of every running motor (0 = none)", "gr.F", -200.0, 200.0),
    "motors.curve_exponent": F("exponent n of the true motor curve F = F_p (V / V_p)^n through the pivot, which the "
                               "controllers (inverting Eq. 40) do not know; 1 = Eq. 40", "", 1.0, 3.0),
    "motors.curve_pivot_grf": F("thrust F_p where the true curve meets Eq. 40; 0 = the hover thrust m g / 4",
                                "gr.F", 0.0, 2000.0),
    "motors.command_steps": I("ESC command resolution: levels over 0..voltage_max (0 = continuous)", 0, 1_000_000),
    "motors.esc_deadband_v": F("ESC dead-band: voltage commands below this give 0 V (0 = none)", "V", 0.0, 10.0),
    "motors.thrust_loop_time_constant": F("the firmware's load-cell thrust loop (a reading of Sec. 3-3, "
                                          "control/thrust_loop.py): time constant at which each motor's correction "
                                          "removes the error between its desired and its filtered load-cell thrust; "
                                          "0 = open loop (Eq. 40 inverse alone); else at least 1 s (a slow loop "
                                          "against the 50 ms motor lag and the 80 ms load-cell filter)",
                                          "s", 0.0, 1e4, gap_to=1.0, off="open loop"),
    "motors.thrust_loop_limit_grf": F("bound on each motor's thrust-loop correction (a stuck or dead load cell "
                                      "cannot drive it further)", "gr.F", 0.0, 850.0),
    "motors.kv_rpm_per_v": F("motor velocity constant KV (Sec. 4: 750 KV); sizes the current the motors draw "
                             "from the bench supply (physics/electrical.py)", "rpm/V", 1.0, 1e5),
    # --- control ---------------------------------------------------------------------------
    "control.strategy": S("controller strategy", STRATEGIES),
    "controller.plugin": Spec("str", "controller plug-in 'package.module:Name' flying instead of (part of) the strategy "
                                     "(docs/how-to/your-controller.md); empty: the built-in strategy alone",
                             values="'package.module:Name', or empty"),
    "controller.params": Spec("params", "the plug-in's own parameters (name = number or list of numbers) over its defaults; "
                                       "one at a time: --set controller.params.NAME=VALUE; listed below with "
                                       "--controller (or a controller.plugin)"),
    "controller.call": S("how a compiled plug-in runs: 'compiled' (inside the compiled loop) or 'python' (its kernel as "
                         "plain Python, e.g. to debug it)", ("compiled", "python")),
    "control.max_tilt_deg": F("tilt limit of the Eq. 35 singularity guard", "deg", 1.0, 80.0),
    "control.reference_time_constant": F(
        "time constant of the filter that gives desired-attitude rates and accelerations", "s", 0.0, 1.0, lo_open=True
    ),
    "control.allocation_priority": S("what gives way when the A6 inverse leaves a motor outside [0, its ceiling]: "
                                     "'attitude' roll/pitch kept, the collective u1 shifted to fit (ideal plant); "
                                     "'thrust' u1 kept, the roll/pitch differential scaled down (Sec. 3-3 computes u1 "
                                     "first; docs/explanation/readings.md); 'clip' no priority, each motor clipped "
                                     "to [0, its ceiling] on its own (a plain firmware: Sec. 3-3's A6 and Eq. 40 "
                                     "inverses, the supply capping each motor)", ("attitude", "thrust", "clip")),
    "control.actuation_delay": F("sensing-to-actuation delay: computation, PWM frame, ESC update; rounded to whole "
                                 "physics steps (0 = none)", "s", 0.0, 0.1),
    "controller_model.inertia_scale": V3("the inertia the controllers' model believes / the true Ixx, Iyy, Izz "
                                         "(1 = exact)", "", 0.1, 10.0),
    "controller_model.arm_length_scale": F("the arm length the controllers believe / the true one (1 = exact)",
                                           "", 0.1, 10.0),
    "controller_model.thrust_per_volt_scale": F("the Eq. 40 slope the controllers invert / the true one (1 = exact)",
                                                "", 0.1, 10.0),
    "smc.gain_reading": S("unit of Eq. 41's K: 'si' rad/s^2 (K as printed), 'thrust' a thrust difference in N "
                          "(switching torque K l, yaw K kM/kF), 'torque' a torque in N m (docs/explanation/readings.md)",
                          ("si", "thrust", "torque")),
    "smc.lambda_reading": S("unit of Eq. 41's lambda: 'si' 1/s, 'deg' applied to angles in degrees against rates "
                            "in rad/s (lambda 180/pi in SI), 'time-constant' seconds (1/lambda in SI)",
                            ("si", "deg", "time-constant")),
    "smc.k": V3("switching gains K (Eq. 9, Eq. 41) for phi, theta, psi", "rad/s^2", 0.0, 1e4),
    "smc.lam": V3("sliding-surface slopes lambda (Eq. 5, Eq. 41) for phi, theta, psi", "1/s", 0.0, 1e4),
    "smc.switching": S("switching function: 'sgn' (paper-faithful) or 'boundary' (sat(s/Phi))", ("sgn", "boundary")),
    "smc.boundary_layer": F("boundary-layer width Phi for 'boundary' switching", "rad/s", 0.0, 100.0, lo_open=True),
    "smc.position_k": V3("position SMC switching gains (strategy 'smc') for X, Y, Z", "m/s^2", 0.0, 1e3),
    "smc.position_lam": V3("position SMC surface slopes for X, Y, Z", "1/s", 0.0, 1e3),
    "smc.position_boundary_layer": F("position SMC boundary layer", "m/s", 0.0, 100.0, lo_open=True),
    "flc.r": FS("membership ratios r1..r4 (Fig. 5; d0 = r1 d1, d2 = r2 d1, d3 = r3 d1, dt = r4 d1)", "", 0.0, 10.0, 4),
    "flc.geometry": S("input membership geometry: 'paper' (RIG-SPEC Reading) or 'even'", ("paper", "even")),
    "flc.d1_phi_deg": F("d1 of roll error (Table 3)", "deg", 0.0, 90.0, lo_open=True),
    "flc.d1_theta_deg": F("d1 of pitch error (Table 3)", "deg", 0.0, 90.0, lo_open=True),
    "flc.d1_psi_deg": F("d1 of yaw error (Table 3)", "deg", 0.0, 90.0, lo_open=True),
    "flc.d1_dphi_deg_s": F("d1 of roll-rate error (Table 3)", "deg/s", 0.0, 1e4, lo_open=True),
    "flc.d1_dtheta_deg_s": F("d1 of pitch-rate error (Table 3)", "deg/s", 0.0, 1e4, lo_open=True),
    "flc.d1_dpsi_deg_s": F("d1 of yaw-rate error (Table 3)", "deg/s", 0.0, 1e4, lo_open=True),
    "flc.d1_u2": F("d1 of output u2 (Table 3)", "N m", 0.0, 1e3, lo_open=True),
    "flc.d1_u3": F("d1 of output u3 (Table 3)", "N m", 0.0, 1e3, lo_open=True),
    "flc.d1_u4": F("d1 of output u4 (Table 3)", "N m", 0.0, 1e3, lo_open=True),
    "flc.d1_x": F("d1 of X error (Table 5)", "m", 0.0, 1e3, lo_open=True),
    "flc.d1_y": F("d1 of Y error (Table 5)", "m", 0.0, 1e3, lo_open=True),
    "flc.d1_z": F("d1 of Z error (Table 5)", "m", 0.0, 1e3, lo_open=True),
    "flc.d1_dx": F("d1 of X-rate error (Table 5)", "m/s", 0.0, 1e3, lo_open=True),
    "flc.d1_dy": F("d1 of Y-rate error (Table 5)", "m/s", 0.0, 1e3, lo_open=True),
    "flc.d1_dz": F("d1 of Z-rate error (Table 5)", "m/s", 0.0, 1e3, lo_open=True),
    "flc.d1_u1": F("d1 of output u1, a correction about hover thrust (Table 5)", "N", 0.0, 1e3, lo_open=True),
    "flc.d1_ux": F("d1 of virtual input uX (Table 5)", "", 0.0, 1.0, lo_open=True),
    "flc.d1_uy": F("d1 of virtual input uY (Table 5)", "", 0.0, 1.0, lo_open=True),
    "flc.position_rate_share": F("share of the desired velocity in the position FLC's error rate: 1 derivative on "
                                 "the error (v_des - v), 0 derivative on the measurement (-v); position errors only: a velocity "
                                 "set-point with no position is tracked as v_des - v", "", 0.0, 1.0),
    "pid.attitude_kp": V3("attitude PID proportional gains", "1/s^2", 0.0, 1e5),
    "pid.attitude_ki": V3("attitude PID integral gains", "1/s^3", 0.0, 1e5),
    "pid.attitude_kd": V3("attitude PID derivative gains", "1/s", 0.0, 1e5),
    "pid.position_kp": V3("position PID proportional gains", "1/s^2", 0.0, 1e4),
    "pid.position_ki": V3("position PID integral gains", "1/s^3", 0.0, 1e4),
    "pid.position_kd": V3("position PID derivative gains", "1/s", 0.0, 1e4),
    "pid.integral_limit": F("anti-windup limit of every PID integrator (in the integrated error's unit x s)", "", 0.0, 1e3),
    # --- guidance ----------------------------------------------------------------------------
    "guidance.type": S("what the rig follows", GUIDANCE_TYPES),
    "guidance.hover_position": V3("hover set-point (world ENU)", "m"),
    "guidance.yaw_deg": F("desired yaw (the paper keeps it 0)", "deg", -180.0, 180.0),
    "guidance.amplitude_deg": V3("harmonic attitude amplitudes for phi, theta, psi (Eq. 44)", "deg", 0.0, 80.0),
    "guidance.omega": F("harmonic attitude frequency (Eq. 44)", "rad/s", 0.0, 1e3, lo_open=True),
    "guidance.waypoints": Spec("floats", "waypoints as [[x, y, z], ...] in world ENU", "m",
                               values="a list of [x, y, z], each coordinate in [-1e+05, 1e+05]"),  # loader._check_waypoints
    "guidance.speed": F("waypoint leg speed that sizes each virtual line (Sec. 4-4)", "m/s", 0.0, 100.0, lo_open=True),
    "guidance.max_speed": F("speed limit of every leg: the cruise speed, DO_CHANGE_SPEED, DO_REPOSITION and mission "
                            "leg speeds above it are flown at it (PX4's MPC_XY_VEL_MAX)", "m/s", 0.0, 100.0, lo_open=True),
    "guidance.switching_radius": F("switch to the next waypoint below this position error (Sec. 4-4)", "m", 0.0, 100.0, lo_open=True),
    "guidance.min_leg_time": F("shortest time a virtual line may take", "s", 0.0, 1e4, lo_open=True),
    # flight tasks (guidance/flight_tasks.py): take-off, land, return (PX4's MIS_TAKEOFF_ALT, RTL_RETURN_ALT, MPC_LAND_SPEED)
    "guidance.takeoff_altitude": F("take-off altitude above home when a take-off command gives none", "m", 0.0, 1e3,
                                   lo_open=True),
    "guidance.return_altitude": F("a return to home climbs to this altitude above home first if lower", "m", 0.0,
                                  1e3, lo_open=True),
    "guidance.land_speed": F("descent speed of a landing (land, return)", "m/s", 0.0, 10.0, lo_open=True),
    # --- MAVLink missions ------------------------------------------------------------------------
    "mission.item0_home": Spec("bool", "treat mission item 0 as home, stored but not flown (ArduPilot's "
                               "convention, for MAVProxy's wp load); false: every item is flown (PX4's)"),
    "mission.max_leg_m": F("longest leg an uploaded mission may have, the first leg measured from home (PX4's "
                           "MIS_DIST_WPS / MIS_DIST_1WP); a longer one is refused at upload", "m", 1.0, 1e7),
    # --- geofence (protocol/mission_checks.py, link fence monitor) ------------------------------------
    "fence.enabled": Spec("bool", "geofence on: missions reaching outside are refused at upload, a breach in flight "
                          "triggers fence.action"),
    "fence.action": S("on a breach, PX4's GF_ACTION codes: 'none', 'warning' (STATUSTEXT only), 'hold' (hold "
                      "position), 'return' (return to launch), 'terminate' (motors off, disarm), 'land'",
                      FENCE_ACTIONS),
    "fence.radius": F("largest horizontal distance from home (ArduPilot FENCE_RADIUS)", "m", 1.0, 1e6),
    "fence.alt_max": F("highest altitude above home (ArduPilot FENCE_ALT_MAX)", "m", -1e4, 1e5),
    "fence.alt_min": F("lowest altitude above home (ArduPilot FENCE_ALT_MIN)", "m", -1e4, 1e5),
    # --- offboard set-points (link offboard monitor) -------------------------------------------------
    "offboard.loss_timeout": F("offboard set-point timeout: no set-point for this long (simulated time) in "
                               "OFFBOARD triggers offboard.loss_action (PX4 COM_OF_LOSS_T)", "s", 0.0, 60.0,
                               lo_open=True),
    "offboard.loss_action": S("on an offboard set-point timeout, PX4's COM_OBL_ACT codes: 'land', 'hold', "
                              "'return', 'terminate' (motors off, disarm)", OFFBOARD_LOSS_ACTIONS),
    # --- initial state -------------------------------------------------------------------------
    "initial.position": V3("initial virtual position (world ENU)", "m"),
    "initial.euler_deg": V3("initial phi, theta, psi", "deg", -180.0, 180.0),
    # --- sensors and estimation (Sec. 4-1) ----------------------------------------------------
    "sensors.simulate": Spec("bool", "simulate the five IMU modules and four load cells (false: no sensor models at all)"),
    "sensors.feedback": S(
        "what the controllers see: 'estimated' (the rig's sensors and estimators, as on the hardware) or 'ideal' (true state)",
        ("estimated", "ideal"),
    ),
    "sensors.calibration": S(
        "IMU calibration applied to raw readings: 'levenberg-marquardt' (Sec. 4-1) or 'none' (datasheet scaling only)",
        ("levenberg-marquardt", "none"),
    ),
    "sensors.calibration_file": Spec(
        "str", "IMU calibration file to load (from `rig-emulator calibrate`); empty: run the procedure at start-up",
        values="a file path, or empty",
    ),
    "estimation.ensemble": S("combination of the five modules: 'mean' (paper), 'median' or 'robust_mean'", ("mean", "median", "robust_mean")),
    "estimation.load_cell_filter": S("load-cell smoothing after the guards: 'iir' (paper), 'kalman' or 'none'", ("iir", "kalman", "none")),
    "estimation.tau_roll_pitch": F("complementary filter: time constant of the accelerometer tilt correction", "s", 0.0, 1e3, lo_open=True),
    "estimation.tau_yaw": F("complementary filter: time constant of the magnetometer heading correction", "s", 0.0, 1e3, lo_open=True),
    "estimation.accel_lowpass_hz": F("low-pass on the accelerometers before the tilt correction", "Hz", 0.0, 1e3, lo_open=True),
    "estimation.iir_cutoff_hz": F("cut-off of the load cells' IIR low-pass", "Hz", 0.0, 1e3, lo_open=True),
    "estimation.divergence_warning_m": F("divergence report threshold: the served rig says once (console and "
                                         "STATUSTEXT) when its onboard virtual position and the physics vehicle "
                                         "(SIM_STATE) part by more than this, again only after they came back within "
                                         "half of it (docs/explanation/sim-state.md); 0 = never", "m", 0.0, 1e6),
    "sensor_models.mpu6050": Spec("tree", "overrides of presets/sensors/mpu6050.toml (datasheet figures)"),
    "sensor_models.hmc5883l": Spec("tree", "overrides of presets/sensors/hmc5883l.toml"),
    "sensor_models.imu_array": Spec("tree", "overrides of presets/sensors/imu_array.toml (mounting, rates, site field)"),
    "sensor_models.zemic_l6d": Spec("tree", "overrides of presets/sensors/zemic_l6d.toml (load cells)"),
    "sensor_models.estimation": Spec("tree", "overrides of presets/sensors/estimation.toml (calibration procedure, guards, Kalman)"),
    "faults.events": Spec(
        "table_list",
        "device faults switched on at a time (docs/how-to/faults.md): IMU modules, load cells, motors",
        item={
            "t": F("when the fault starts", "s", 0.0),
            "sensor": S("which kind of device", ("imu", "load_cell", "motor")),
            "index": I("IMU module 0..4; load cell or motor 1..4 (the arm number)", 0, 15),
            "mode": S("fault mode: imu none/stuck/dead/bias/noise, load_cell also spike, motor none/dead/thrust_loss",
                      ("none", "stuck", "dead", "bias", "noise", "spike", "thrust_loss")),
            "magnitude": F("bias in counts, noise as a multiple of the nominal sigma, spike in counts, "
                           "thrust_loss the fraction of thrust lost in [0, 1]; unused by none/stuck/dead", "", -1e6, 1e6),
        },
    ),
    # --- supervisor: health monitor and loss-of-control failsafe (control/supervisor.py) ----------------
    "health.update_rate_hz": F("rate of the supervisor (health flags, loss-of-control failsafe), rounded to a whole "
                               "number of control periods", "Hz", 1.0, 1e5),
    "health.reject_window": F("an IMU module or load cell is flagged while the estimators reject it more than half "
                              "of the time, averaged over this time constant (healthy again below a tenth)",
                              "s", 0.0, 60.0, lo_open=True),
    "health.accel_tolerance": F("the fused accelerometer is invalid when its magnitude leaves (1 +- this) g",
                                "", 0.0, 1.0, lo_open=True),
    "health.mag_tolerance": F("the fused magnetometer is invalid when its magnitude leaves (1 +- this) x the site "
                              "field", "", 0.0, 1.0, lo_open=True),
    "failsafe.enabled": Spec("bool", "detect loss of control while armed (false: never trip)"),
    "failsafe.action": S("on loss of control: 'disarm' (motors to 0 V, the rig disarms) or 'report' (flag only)",
                         ("disarm", "report")),
    "failsafe.attitude_error_deg": F("loss of control when the roll or pitch error exceeds this for hold_time",
                                     "deg", 1.0, 180.0),
    "failsafe.rate_limit_deg_s": F("loss of control when the body rate exceeds this for hold_time",
                                   "deg/s", 1.0, 1e5),
    "failsafe.hold_time": F("how long a loss-of-control condition must hold without a break", "s", 0.0, 60.0,
                            lo_open=True),
    "failsafe.on_estimate_invalid": Spec("bool", "loss of control also when the attitude estimate the controllers "
                                         "fly on is invalid (IMU majority lost or implausible) for hold_time"),
    # pre-arm checks (simulation/prearm.py) and the ground-station loss failsafe (link/gcs_loss.py)
    "prearm.max_tilt_deg": F("arming is refused while the roll or pitch estimate exceeds this", "deg", 0.0, 90.0,
                             lo_open=True),
    "prearm.max_rate_deg_s": F("arming is refused while the body-rate estimate exceeds this (the rig still turns)",
                               "deg/s", 0.0, 1e4, lo_open=True),
    "failsafe.gcs_timeout": F("ground station lost when no GCS HEARTBEAT arrived for this long (wall-clock)",
                              "s", 0.0, 3600.0, lo_open=True),
    "failsafe.gcs_action": S("on ground-station loss while armed in a mode that needs one (POSCTL, AUTO.LOITER, "
                             "STABILIZED): 'none', 'hold', 'return', 'land' or 'disarm'",
                             ("none", "hold", "return", "land", "disarm")),
    # --- disturbances ----------------------------------------------------------------------------
    "disturbance.wind_force": V3("constant wind force on the body (world ENU), enters Eq. 1", "N", -1e3, 1e3),
    "disturbance.torque_noise": V3("random body torque (prop wash, cable drag): standard deviation per body axis "
                                   "of first-order coloured noise (0 = none)", "N m", 0.0, 10.0),
    "disturbance.torque_noise_corner_hz": F("corner frequency of the random body torque", "Hz", 0.0, 500.0,
                                            lo_open=True),
    # --- the spherical joint and the frame ----------------------------------------------
    "joint.viscous": V3("viscous friction of the spherical joint per body axis", "N m s/rad", 0.0, 10.0),
    "joint.coulomb": V3("Coulomb friction of the spherical joint per body axis", "N m", 0.0, 10.0),
    "joint.coulomb_smoothing": F("body rate over which the Coulomb friction is smoothed (tanh(w / this))", "rad/s",
                                 0.0, 10.0, lo_open=True),
    "joint.cog_offset": V3("centre of gravity relative to the joint, body FRD (x, y: static imbalance; z > 0 below "
                           "the joint: pendulum, z < 0 above: inverted pendulum)", "m", -0.1, 0.1),
    "vibration.gyro_amplitude": V3("frame vibration per rotor at hover rotor speed reaching every IMU module alike: "
                                   "gyro amplitude per body axis (scales with rotor speed^2)", "rad/s", 0.0, 10.0),
    "vibration.accel_amplitude": V3("frame vibration per rotor at hover rotor speed: accelerometer amplitude per "
                                    "body axis", "m/s^2", 0.0, 100.0),
    "vibration.blades": I("propeller blades (the vibration is at the blade-pass frequency, blades x rotor speed)", 1, 8),
    "motor_field.ripple_uT": F("magnetic field of a motor's current ripple at the IMU modules (the driver's PWM and "
                               "commutation ripple aliased by the magnetometer sampling): rms per sample per motor "
                               "at hover current, horizontal and perpendicular to its arm", "uT", 0.0, 47.0),
    "motor_field.steady_uT": F("steady magnetic field of a motor's supply leads at the IMU modules at hover current, "
                               "horizontal and perpendicular to its arm (opposite arms cancel at equal currents)",
                               "uT", 0.0, 47.0),
    "disturbance.gusts": Spec(
        "table_list",
        "1-cosine gusts added to the wind force",
        item={
            "t": F("start time", "s", 0.0),
            "duration": F("gust length", "s", 0.0, 1e4, lo_open=True),
            "force": V3("peak force (world ENU)", "N", -1e3, 1e3),
        },
    ),
    "disturbance.shocks": Spec(
        "table_list",
        "impulsive torque shocks on an arm (Fig. 12): a rectangular push on the arm tip",
        item={
            "t": F("start time", "s", 0.0),
            "arm": I("arm 1..4 (A6 numbering)", 1, 4),
            "torque": F("torque about the joint; positive pushes the arm tip down", "N m", -100.0, 100.0),
            "duration": F("pulse length", "s", 0.0, 10.0, lo_open=True),
        },
    ),
    "disturbance.extra_masses": Spec(
        "table_list",
        "extra point masses on arms (Fig. 15): shift inertia, add a gravity torque about the joint",
        item={
            "arm": I("arm 1..4 (A6 numbering)", 1, 4),
            "mass": F("mass", "kg", 0.0, 10.0),
            "distance": F("distance from the joint along the arm", "m", 0.0, 5.0),
        },
    ),
}
