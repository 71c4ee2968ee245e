"""What the regression takes as known about the rig: its build and its firmware's settings.

Everything the log does not estimate comes from the base configuration of the fit (``--airframe``,
``--config``, ``--set``, as ``rig-emulator simulate`` takes them): the geometry (arm length, yaw
moment per thrust, rotor thrust coefficient and inertia), Eq. 40's slope and the motor curve's pivot
(the thrust scale the gains are relative to), the motor time constant, the ESC dead-band, the
firmware's rates and its load-cell filter, the Coulomb smoothing rate and the random torque's corner.
An effect that is in the log but held here at a wrong value is what the model checks
(gcs_tools/identify/model_check.py) are for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rig_emulator.physics.motors import GRAM_FORCE_N
from rig_emulator.sensors.load_cell import load_load_cell_config
from rig_emulator.sensors.presets import load_sensor_preset


@dataclass(frozen=True)
class RigConstants:
    v_max: float            # V
    k_v: float              # Eq. 40, N/V
    f_pivot: float          # N: the true curve's pivot thrust
    v_pivot: float          # V
    f_ceiling: float        # N
    tau_motor: float        # s
    deadband: float         # V
    dt: float               # physics step, s
    ctrl_div: int           # physics steps per control update
    lc_decim: int           # physics steps per load-cell sample
    lc_alpha: float         # the load-cell IIR's alpha per sample (0: no filter)
    arm: float              # m
    km: float               # m (yaw moment per thrust)
    kf: float               # N s^2/rad^2
    rotor_inertia: float    # kg m^2
    mass: float             # kg
    g: float                # m/s^2
    inertia: tuple          # preset Ixx, Iyy, Izz (the regression estimates them)
    coulomb_smoothing: float  # rad/s
    noise_corner_hz: float
    lc_noise_floor_N: float
    lc_vibration_N: float
    rotor_speed_hover: float  # rad/s of the load cells' vibration scale
    delay_preset: float     # s (start of the search only)
    lc_jump_N: float        # the load cells' jump guard (estimation/load_cell_filter.py), N
    lc_max_N: float         # the load cells' upper guard: readings above are discarded, N
    lc_reaccept: int        # samples after which the guard accepts a reading again (0: never)


def rig_constants(cfg) -> RigConstants:
    """The constants of a validated :class:`~rig_emulator.config.loader.RigConfig`."""
    k_v = cfg["motors.thrust_per_volt_grf"] * GRAM_FORCE_N
    mass = cfg["airframe.mass"]
    g = cfg["airframe.gravity"]
    f_p = cfg["motors.curve_pivot_grf"] * GRAM_FORCE_N or mass * g / 4.0
    dt = 1.0 / cfg["sim.physics_rate_hz"]
    lc = load_load_cell_config(cfg["sensor_models.zemic_l6d"] or None)["load_cell"]
    est = load_sensor_preset("estimation", cfg["sensor_models.estimation"] or None)["load_cell_filter"]
    decim = int(lc["decimation"])
    mode = cfg["estimation.load_cell_filter"]
    cutoff = cfg["estimation.iir_cutoff_hz"]
    alpha = 1.0 - math.exp(-2.0 * math.pi * cutoff * dt * decim) if mode == "iir" else 0.0
    if mode == "kalman":
        raise ValueError("estimation.load_cell_filter = 'kalman': the regression models the 'iir' and 'none' filters")
    return RigConstants(
        v_max=cfg["motors.voltage_max"], k_v=k_v, f_pivot=f_p, v_pivot=f_p / k_v,
        f_ceiling=cfg["motors.thrust_ceiling_grf"] * GRAM_FORCE_N, tau_motor=cfg["motors.time_constant"],
        deadband=cfg["motors.esc_deadband_v"], dt=dt,
        ctrl_div=int(round(cfg["sim.physics_rate_hz"] / cfg["sim.control_rate_hz"])), lc_decim=decim,
        lc_alpha=alpha, arm=cfg["airframe.arm_length"], km=cfg["airframe.km_over_kf"], kf=cfg["motors.kf"],
        rotor_inertia=cfg["airframe.rotor_inertia"], mass=mass, g=g,
        inertia=(cfg["airframe.ixx"], cfg["airframe.iyy"], cfg["airframe.izz"]),
        coulomb_smoothing=cfg["joint.coulomb_smoothing"], noise_corner_hz=cfg["disturbance.torque_noise_corner_hz"],
        lc_noise_floor_N=lc["noise_floor_grf"] * GRAM_FORCE_N, lc_vibration_N=lc["vibration_grf_at_hover"] * GRAM_FORCE_N,
        rotor_speed_hover=lc["rotor_speed_hover_rad_s"], delay_preset=cfg["control.actuation_delay"],
        lc_jump_N=est["jump_threshold_grf"] * GRAM_FORCE_N, lc_max_N=est["max_thrust_grf"] * GRAM_FORCE_N,
        lc_reaccept=int(est["reaccept_after"]),
    )
