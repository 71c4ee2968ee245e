"""Pack a validated :class:`~rig_emulator.config.loader.RigConfig` into the compiled loop's arguments.

The compiled code receives plain namedtuples of floats and float64 arrays (never module
globals, docs/explanation/conventions.md). This module is the one place where paper units are turned
into SI (degrees -> rad, gram-force -> N) and names into integer codes.
"""

from __future__ import annotations

import functools
import math
from collections import namedtuple

import numpy as np

from rig_emulator.config.loader import ConfigError, RigConfig
from rig_emulator.control import fuzzy
from rig_emulator.control.allocation import PRIORITIES
from rig_emulator.controllers.builtin.strategies import laws
from rig_emulator.guidance.offboard import OFB_SIZE
from rig_emulator.guidance.runner import GUIDANCE_CODES
from rig_emulator.physics.hardware import HardwareParams
from rig_emulator.physics.motors import GRAM_FORCE_N

PhysicsParams = namedtuple(
    "PhysicsParams",
    "mass ixx iyy izz arm_length rotor_inertia km_over_kf g k_v f_ceiling v_max tau_motor kf ground "
    # ground_hold: sim.ground_contact == "hold", the virtual ground's resting contact (physics/ground.py)
    "ground_hold "
    # thrust_efficiency: (4,) share of Eq. 40's thrust each motor produces (motor faults);
    # hw: HardwareParams, the real rig's effects (physics/hardware.py)
    "thrust_efficiency hw",
)

ControlParams = namedtuple(
    "ControlParams",
    "pos_law att_law mass g ixx iyy izz arm_length rotor_inertia km_over_kf kf k_v v_max f_max "
    "max_tilt ref_omega smc_k smc_lam smc_boundary smc_phi smcp_k smcp_lam smcp_phi "
    "flc_phi flc_theta flc_psi flc_x flc_y flc_z rule_table flc_rate_share "
    "pida_kp pida_ki pida_kd pidp_kp pidp_ki pidp_kd pid_limit "
    "thrust_loop_rate thrust_loop_limit "  # the load-cell thrust loop (control/thrust_loop.py): 1/T (0 = off), N
    "alloc_priority",  # control.allocation_priority as a PRIORITY_* int (control/allocation.py)
)

GuidanceParams = namedtuple(
    "GuidanceParams",
    "gtype hover_position yaw amplitude omega att_offset waypoints radii holds speeds free_xy speed min_leg_time "
    "offboard",  # (OFB_SIZE,) the offboard set-point (guidance/offboard.py), used when gtype is OFFBOARD
)

Disturbances = namedtuple("Disturbances", "wind gusts shocks extra")


def _arr(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


def _hover_rotor_speed(cfg: RigConfig) -> float:
    return math.sqrt(cfg["airframe.mass"] * cfg["airframe.gravity"] / 4.0 / cfg["motors.kf"])


def hardware_params(cfg: RigConfig, k_v: float, dt: float, previous: HardwareParams | None = None) -> HardwareParams:
    """The real rig's effects from the config; SI here (gr.F -> N, seconds -> steps).

    ``previous``: the running rig's HardwareParams whose state (command buffer, noise, phases,
    random stream) a parameter change keeps when its shape allows.
    """
    visc = _arr(cfg["joint.viscous"])
    coul = _arr(cfg["joint.coulomb"])
    cog = _arr(cfg["joint.cog_offset"])
    delay_steps = int(round(cfg["control.actuation_delay"] / dt))
    steps = cfg["motors.command_steps"]
    v_max = supply_voltage(cfg)
    quantum = v_max / steps if steps > 0 else 0.0
    deadband = cfg["motors.esc_deadband_v"]
    pivot = cfg["motors.curve_pivot_grf"] * GRAM_FORCE_N
    if pivot == 0.0:
        pivot = cfg["airframe.mass"] * cfg["airframe.gravity"] / 4.0
    sigma = _arr(cfg["disturbance.torque_noise"])
    a = math.exp(-2.0 * math.pi * cfg["disturbance.torque_noise_corner_hz"] * dt)
    vg = _arr(cfg["vibration.gyro_amplitude"])
    va = _arr(cfg["vibration.accel_amplitude"])
    act_on = delay_steps > 0 or quantum > 0.0 or deadband > 0.0
    if previous is not None and previous.cmd_buf.shape[0] == delay_steps + 1:
        cmd_buf, cmd_out, noise, rng, phase = (previous.cmd_buf, previous.cmd_out, previous.noise_torque,
                                               previous.rng, previous.vib_phase)
    else:
        cmd_buf = np.zeros((delay_steps + 1, 4))
        cmd_out = np.zeros(4)
        noise = np.zeros(3) if previous is None else previous.noise_torque
        rng = (np.random.SeedSequence([cfg["sim.seed"], 13]).generate_state(1, np.uint64) if previous is None
               else previous.rng)
        phase = (0.5 * math.pi * np.arange(4.0)) if previous is None else previous.vib_phase
    return HardwareParams(
        friction=bool(np.any(visc > 0.0) or np.any(coul > 0.0)),
        visc=visc,
        coul=coul,
        coul_rate=cfg["joint.coulomb_smoothing"],
        cog_on=bool(np.any(cog != 0.0)),
        cog_moment=cfg["airframe.mass"] * cog,
        gain=_arr(cfg["motors.thrust_gain"]),
        bias=cfg["motors.thrust_bias_grf"] * GRAM_FORCE_N,
        curve_n=cfg["motors.curve_exponent"],
        curve_vp=pivot / k_v,
        curve_fp=pivot,
        act_on=act_on,
        delay_steps=delay_steps,
        cmd_buf=cmd_buf,
        cmd_out=cmd_out,
        quantum=quantum,
        deadband=deadband,
        noise_on=bool(np.any(sigma > 0.0)),
        noise_sigma=sigma,
        noise_a=a,
        noise_b=math.sqrt(1.0 - a * a),
        noise_torque=noise,
        rng=rng,
        vib_on=bool(np.any(vg > 0.0) or np.any(va > 0.0)),
        vib_gyro=vg,
        vib_acc=va,
        vib_blades=float(cfg["vibration.blades"]),
        vib_omega_ref=_hover_rotor_speed(cfg),
        vib_phase=phase,
        mag_ripple=cfg["motor_field.ripple_uT"] * 1e-6,
        mag_steady=cfg["motor_field.steady_uT"] * 1e-6,
        curve_memo=np.full((4, 2), np.nan),
    )


def supply_voltage(cfg: RigConfig) -> float:
    """The motors' supply ceiling (Fig. 11), V."""
    return cfg["motors.voltage_max"]


def physics_params(cfg: RigConfig, thrust_efficiency: np.ndarray | None = None,
                   previous_hw: HardwareParams | None = None) -> PhysicsParams:
    """Physics arguments; ``thrust_efficiency`` (4,) is the motor-fault array to keep (default: all
    healthy), ``previous_hw`` the running rig's hardware-effect state to keep."""
    k_v = cfg["motors.thrust_per_volt_grf"] * GRAM_FORCE_N
    return PhysicsParams(
        mass=cfg["airframe.mass"],
        ixx=cfg["airframe.ixx"],
        iyy=cfg["airframe.iyy"],
        izz=cfg["airframe.izz"],
        arm_length=cfg["airframe.arm_length"],
        rotor_inertia=cfg["airframe.rotor_inertia"],
        km_over_kf=cfg["airframe.km_over_kf"],
        g=cfg["airframe.gravity"],
        k_v=k_v,
        f_ceiling=cfg["motors.thrust_ceiling_grf"] * GRAM_FORCE_N,
        v_max=cfg["motors.voltage_max"],
        tau_motor=cfg["motors.time_constant"],
        kf=cfg["motors.kf"],
        ground=bool(cfg["sim.ground"]),
        ground_hold=cfg["sim.ground_contact"] == "hold",
        thrust_efficiency=np.ones(4) if thrust_efficiency is None else thrust_efficiency,
        hw=hardware_params(cfg, k_v, 1.0 / cfg["sim.physics_rate_hz"], previous_hw),
    )


@functools.lru_cache(maxsize=512)
def _shared_axis(d1_e: float, d1_de: float, d1_u: float, r: tuple, geometry: str):
    return fuzzy.make_axis(d1_e, d1_de, d1_u, r=r, geometry=geometry)


def _flc_axes(cfg: RigConfig):
    r = tuple(cfg["flc.r"])
    geo = cfg["flc.geometry"]
    deg = math.radians

    def axis(d1_e, d1_de, d1_u):
        # built once per process for each geometry (many runs of a sweep share it); every rig
        # gets its own arrays
        shared = _shared_axis(float(d1_e), float(d1_de), float(d1_u), r, geo)
        return type(shared)(*(np.array(a, copy=True) for a in shared))

    return dict(
        flc_phi=axis(deg(cfg["flc.d1_phi_deg"]), deg(cfg["flc.d1_dphi_deg_s"]), cfg["flc.d1_u2"]),
        flc_theta=axis(deg(cfg["flc.d1_theta_deg"]), deg(cfg["flc.d1_dtheta_deg_s"]), cfg["flc.d1_u3"]),
        flc_psi=axis(deg(cfg["flc.d1_psi_deg"]), deg(cfg["flc.d1_dpsi_deg_s"]), cfg["flc.d1_u4"]),
        flc_x=axis(cfg["flc.d1_x"], cfg["flc.d1_dx"], cfg["flc.d1_ux"]),
        flc_y=axis(cfg["flc.d1_y"], cfg["flc.d1_dy"], cfg["flc.d1_uy"]),
        flc_z=axis(cfg["flc.d1_z"], cfg["flc.d1_dz"], cfg["flc.d1_u1"]),
    )


def smc_gains_si(cfg: RigConfig, ixx: float, iyy: float, izz: float, arm_length: float,
                 km_over_kf: float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 41's K and lambda in the SI units the SMC of Eq. 9 uses, by their readings.

    ``smc.gain_reading``: 'si' K in rad/s^2 as printed; 'thrust' K is a thrust difference in
    N, so the switching torque is ``K l`` (roll, pitch) or ``K kM/kF`` (yaw, A6) and
    ``K_SI = K l / I``; 'torque' K is a torque in N m, ``K_SI = K / I``. ``smc.lambda_reading``:
    'si' lambda in 1/s; 'deg' lambda multiplies the angle error in degrees against rates in
    rad/s (firmware keeping its complementary filter's angles in degrees), so
    ``lambda_SI = lambda 180 / pi``; 'time-constant' lambda is the surface's time constant in
    s, ``lambda_SI = 1 / lambda``. The inertia and arm length are the controllers' own
    (their model, ``controller_model.*``).
    """
    k = _arr(cfg["smc.k"])
    lam = _arr(cfg["smc.lam"])
    reading = cfg["smc.gain_reading"]
    if reading == "thrust":
        k = k * np.array([arm_length / ixx, arm_length / iyy, km_over_kf / izz])
    elif reading == "torque":
        k = k / np.array([ixx, iyy, izz])
    lr = cfg["smc.lambda_reading"]
    if lr == "deg":
        lam = lam * (180.0 / math.pi)
    elif lr == "time-constant":
        lam = np.where(lam > 0.0, 1.0 / np.where(lam > 0.0, lam, 1.0), 0.0)
    return _arr(k), _arr(lam)


def _thrust_loop_rate(cfg: RigConfig) -> float:
    """1 / ``motors.thrust_loop_time_constant`` (1/s), 0 with the loop off (time constant 0)."""
    tc = cfg["motors.thrust_loop_time_constant"]
    return 1.0 / tc if tc > 0.0 else 0.0


def control_params(cfg: RigConfig) -> ControlParams:
    """The controllers' arguments: what the firmware believes (its model, ``controller_model.*``)."""
    pp = physics_params(cfg)
    pos_law, att_law = laws(cfg["control.strategy"])
    inertia = cfg["controller_model.inertia_scale"]
    ixx = pp.ixx * inertia[0]
    iyy = pp.iyy * inertia[1]
    izz = pp.izz * inertia[2]
    arm_length = pp.arm_length * cfg["controller_model.arm_length_scale"]
    k_v = pp.k_v * cfg["controller_model.thrust_per_volt_scale"]
    smc_k, smc_lam = smc_gains_si(cfg, ixx, iyy, izz, arm_length, pp.km_over_kf)
    return ControlParams(
        pos_law=pos_law,
        att_law=att_law,
        mass=pp.mass,
        g=pp.g,
        ixx=ixx,
        iyy=iyy,
        izz=izz,
        arm_length=arm_length,
        rotor_inertia=pp.rotor_inertia,
        km_over_kf=pp.km_over_kf,
        kf=pp.kf,
        k_v=k_v,
        v_max=pp.v_max,
        f_max=min(pp.f_ceiling, k_v * pp.v_max),
        max_tilt=math.radians(cfg["control.max_tilt_deg"]),
        ref_omega=1.0 / cfg["control.reference_time_constant"],
        smc_k=smc_k,
        smc_lam=smc_lam,
        smc_boundary=cfg["smc.switching"] == "boundary",
        smc_phi=cfg["smc.boundary_layer"],
        smcp_k=_arr(cfg["smc.position_k"]),
        smcp_lam=_arr(cfg["smc.position_lam"]),
        smcp_phi=cfg["smc.position_boundary_layer"],
        rule_table=fuzzy.RULE_TABLE,
        flc_rate_share=cfg["flc.position_rate_share"],
        pida_kp=_arr(cfg["pid.attitude_kp"]),
        pida_ki=_arr(cfg["pid.attitude_ki"]),
        pida_kd=_arr(cfg["pid.attitude_kd"]),
        pidp_kp=_arr(cfg["pid.position_kp"]),
        pidp_ki=_arr(cfg["pid.position_ki"]),
        pidp_kd=_arr(cfg["pid.position_kd"]),
        pid_limit=cfg["pid.integral_limit"],
        thrust_loop_rate=_thrust_loop_rate(cfg),
        thrust_loop_limit=cfg["motors.thrust_loop_limit_grf"] * GRAM_FORCE_N,
        alloc_priority=PRIORITIES[cfg["control.allocation_priority"]],
        **_flc_axes(cfg),
    )


def guidance_params(cfg: RigConfig, waypoints=None, radii=None, holds=None, speeds=None, free_xy=None) -> GuidanceParams:
    """Guidance arguments; ``waypoints``/``radii``/``holds``/``speeds``/``free_xy`` override the
    config's (missions). Per waypoint: a radius or speed of 0 means the configured
    ``guidance.switching_radius`` / ``guidance.speed``; ``free_xy`` 1 takes the target's X and Y
    from where the rig is when the leg starts (take-off, landing in place)."""
    wp = _arr(cfg["guidance.waypoints"] if waypoints is None else waypoints).reshape(-1, 3)
    if wp.shape[0] == 0:
        wp = np.zeros((1, 3))
    n = wp.shape[0]
    default_r = cfg["guidance.switching_radius"]
    r = np.full(n, default_r) if radii is None else _arr(radii)
    r = np.where(r > 0.0, r, default_r)
    h = np.zeros(n) if holds is None else _arr(holds)
    v = np.zeros(n) if speeds is None else _arr(speeds)
    f = np.zeros(n) if free_xy is None else _arr(free_xy)
    for name, a in (("radii", r), ("holds", h), ("speeds", v), ("free_xy", f)):
        if a.shape != (n,):
            raise ValueError(f"{name}: expected {n} values (one per waypoint), got shape {a.shape}")
    return GuidanceParams(
        gtype=GUIDANCE_CODES[cfg["guidance.type"]],
        hover_position=_arr(cfg["guidance.hover_position"]),
        yaw=math.radians(cfg["guidance.yaw_deg"]),
        amplitude=np.radians(_arr(cfg["guidance.amplitude_deg"])),
        omega=cfg["guidance.omega"],
        att_offset=np.zeros(3),
        waypoints=wp,
        radii=r,
        holds=h,
        speeds=np.minimum(v, cfg["guidance.max_speed"]),  # PX4's MPC_XY_VEL_MAX caps every leg
        free_xy=f,
        speed=min(cfg["guidance.speed"], cfg["guidance.max_speed"]),
        min_leg_time=cfg["guidance.min_leg_time"],
        offboard=np.full(OFB_SIZE, np.nan),
    )


def disturbances(cfg: RigConfig) -> Disturbances:
    gusts = [[g["t"], g["duration"], *g["force"]] for g in cfg["disturbance.gusts"]]
    shocks = [[s["t"], s["arm"], s["torque"], s["duration"]] for s in cfg["disturbance.shocks"]]
    extra = np.zeros((4, 2))
    for i, m in enumerate(cfg["disturbance.extra_masses"]):
        if extra[m["arm"] - 1, 0] != 0.0:
            raise ConfigError(f"disturbance.extra_masses[{i}].arm = {m['arm']}: that arm already carries a mass")
        extra[m["arm"] - 1, 0] = m["mass"]
        extra[m["arm"] - 1, 1] = m["distance"]
    return Disturbances(
        wind=_arr(cfg["disturbance.wind_force"]),
        gusts=_arr(gusts).reshape(-1, 5),
        shocks=_arr(shocks).reshape(-1, 4),
        extra=extra,
    )
