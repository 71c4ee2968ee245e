"""Pack a validated :class:`~rig_emulator.config.loader.RigConfig` into the compiled loop's arguments.

The compiled code receives plain namedtuples of floats and float64 arrays (never module
globals, docs/CONVENTIONS.md). This module is the one place where paper units are turned
into SI (degrees -> rad, gram-force -> N) and names into integer codes.
"""

from __future__ import annotations

import functools
import math
from collections import namedtuple

import numpy as np

from rig_emulator.config.loader import ConfigError, RigConfig
from rig_emulator.control import fuzzy
from rig_emulator.control.strategies import laws
from rig_emulator.guidance.offboard import OFB_SIZE
from rig_emulator.guidance.runner import GUIDANCE_CODES
from rig_emulator.physics.motors import GRAM_FORCE_N

PhysicsParams = namedtuple(
    "PhysicsParams",
    "mass ixx iyy izz arm_length rotor_inertia km_over_kf g k_v f_ceiling v_max tau_motor kf ground "
    "thrust_efficiency",  # (4,) share of Eq. 40's thrust each motor produces (motor faults)
)

ControlParams = namedtuple(
    "ControlParams",
    "pos_law att_law mass g ixx iyy izz arm_length rotor_inertia km_over_kf kf k_v v_max f_max "
    "max_tilt ref_omega smc_k smc_lam smc_boundary smc_phi smcp_k smcp_lam smcp_phi "
    "flc_phi flc_theta flc_psi flc_x flc_y flc_z rule_table "
    "pida_kp pida_ki pida_kd pidp_kp pidp_ki pidp_kd pid_limit",
)

GuidanceParams = namedtuple(
    "GuidanceParams",
    "gtype hover_position yaw amplitude omega att_offset waypoints radii holds speeds free_xy speed min_leg_time "
    "offboard",  # (OFB_SIZE,) the offboard set-point (guidance/offboard.py), used when gtype is OFFBOARD
)

Disturbances = namedtuple("Disturbances", "wind gusts shocks extra")


def _arr(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


def physics_params(cfg: RigConfig, thrust_efficiency: np.ndarray | None = None) -> PhysicsParams:
    """Physics arguments; ``thrust_efficiency`` (4,) is the motor-fault array to keep (default: all healthy)."""
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
        thrust_efficiency=np.ones(4) if thrust_efficiency is None else thrust_efficiency,
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


def control_params(cfg: RigConfig) -> ControlParams:
    pp = physics_params(cfg)
    pos_law, att_law = laws(cfg["control.strategy"])
    return ControlParams(
        pos_law=pos_law,
        att_law=att_law,
        mass=pp.mass,
        g=pp.g,
        ixx=pp.ixx,
        iyy=pp.iyy,
        izz=pp.izz,
        arm_length=pp.arm_length,
        rotor_inertia=pp.rotor_inertia,
        km_over_kf=pp.km_over_kf,
        kf=pp.kf,
        k_v=pp.k_v,
        v_max=pp.v_max,
        f_max=min(pp.f_ceiling, pp.k_v * pp.v_max),
        max_tilt=math.radians(cfg["control.max_tilt_deg"]),
        ref_omega=1.0 / cfg["control.reference_time_constant"],
        smc_k=_arr(cfg["smc.k"]),
        smc_lam=_arr(cfg["smc.lam"]),
        smc_boundary=cfg["smc.switching"] == "boundary",
        smc_phi=cfg["smc.boundary_layer"],
        smcp_k=_arr(cfg["smc.position_k"]),
        smcp_lam=_arr(cfg["smc.position_lam"]),
        smcp_phi=cfg["smc.position_boundary_layer"],
        rule_table=fuzzy.RULE_TABLE,
        pida_kp=_arr(cfg["pid.attitude_kp"]),
        pida_ki=_arr(cfg["pid.attitude_ki"]),
        pida_kd=_arr(cfg["pid.attitude_kd"]),
        pidp_kp=_arr(cfg["pid.position_kp"]),
        pidp_ki=_arr(cfg["pid.position_ki"]),
        pidp_kd=_arr(cfg["pid.position_kd"]),
        pid_limit=cfg["pid.integral_limit"],
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
        speeds=v,
        free_xy=f,
        speed=cfg["guidance.speed"],
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
