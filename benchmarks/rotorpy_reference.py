"""RotorPy 3.0.0 as the speed reference for a quadrotor simulation loop.

The reference figure is RotorPy's *bare control loop* at 1 kHz with its IMU: its
``Multirotor`` vehicle with the quadrotor parameters it ships and uses in its own
examples (``rotorpy.vehicles.crazyflie_params``), its ``SE3Control`` controller, a
``HoverTraj`` trajectory and its ``Imu`` sensor sampled every step, ``dt = 1 ms``.

Each step does exactly the per-step work of ``rotorpy.simulate.simulate`` that
belongs to the control loop and the IMU, in the same order::

    t += dt
    state   = vehicle.step(state, control, dt)          # solve_ivp (RK45) over one step
    flat    = trajectory.update(t)
    control = controller.update(t, state, flat)
    sdot    = vehicle.statedot(state, control, dt)      # accelerations the IMU needs
    imu     = imu.measurement(state, sdot, with_noise=True)

and leaves out what ``simulate`` adds around it: the wind profile (``NoWind``), motion
capture, the null estimator, the second noise-free IMU call, the safety/exit checks
and appending every quantity to history lists. Real-time factor = simulated seconds /
wall seconds of the timed steps (a few warm-up steps are timed separately).

``rotorpy-simulate`` measures RotorPy's own ``simulate()`` with the same components
and its defaults for the rest, for context.
"""

from __future__ import annotations

import math
import time

from .harness import BenchmarkUnavailable, Metric, ProbeStats, benchmark, paired_ratio_metric, probe

ROTORPY_BARE = "rotorpy-1khz-imu"
ROTORPY_SIMULATE = "rotorpy-simulate-1khz"

# The figure recorded in the project's performance notes, for comparison only.
NOTED_RTF = 0.64


def _import_rotorpy():
    try:
        import numpy as np
        from rotorpy.controllers.quadrotor_control import SE3Control
        from rotorpy.sensors.imu import Imu
        from rotorpy.trajectories.hover_traj import HoverTraj
        from rotorpy.vehicles.crazyflie_params import quad_params
        from rotorpy.vehicles.multirotor import Multirotor
    except ImportError as exc:
        raise BenchmarkUnavailable(
            f"RotorPy is not importable ({exc}); install the reference with "
            f"`pip install -e '.[bench]'` (rotorpy==3.0.0)"
        ) from None
    from importlib import metadata

    version = metadata.version("rotorpy")
    return np, Multirotor, quad_params, SE3Control, HoverTraj, Imu, version


def _build(dt: float):
    np, Multirotor, quad_params, SE3Control, HoverTraj, Imu, version = _import_rotorpy()
    vehicle = Multirotor(quad_params)  # default initial state: at the origin, hover rotor speeds
    controller = SE3Control(quad_params)
    x0 = np.array(vehicle.initial_state["x"], dtype=float)
    trajectory = HoverTraj(x0=x0)
    imu = Imu(p_BS=np.zeros(3), R_BS=np.eye(3), sampling_rate=round(1.0 / dt))
    state = {k: np.array(v) for k, v in vehicle.initial_state.items()}
    return np, vehicle, controller, trajectory, imu, state, x0, version


@probe(ROTORPY_BARE, params={"duration": 3.0, "dt": 0.001, "seed": 0, "warmup_steps": 100},
       quick={"duration": 0.3, "warmup_steps": 20},
       description="RotorPy 3.0.0 bare 1 kHz control loop with its IMU (hover)")
def rotorpy_bare_loop(duration: float, dt: float, seed: int, warmup_steps: int) -> dict:
    """RotorPy's bare control loop with its IMU; see the module docstring."""
    t_import = time.perf_counter()
    np, vehicle, controller, trajectory, imu, state, x0, version = _build(dt)
    setup_s = time.perf_counter() - t_import
    np.random.seed(seed)

    t = 0.0
    flat = trajectory.update(t)
    control = controller.update(t, state, flat)
    sdot = vehicle.statedot(state, control, dt)
    meas = imu.measurement(state, sdot, with_noise=True)

    def run(n: int):
        nonlocal t, state, flat, control, sdot, meas
        for _ in range(n):
            t += dt
            state = vehicle.step(state, control, dt)
            flat = trajectory.update(t)
            control = controller.update(t, state, flat)
            sdot = vehicle.statedot(state, control, dt)
            meas = imu.measurement(state, sdot, with_noise=True)

    w0 = time.perf_counter()
    run(warmup_steps)
    warm_s = time.perf_counter() - w0
    steps = int(round(duration / dt))
    if steps < 1:
        raise ValueError(f"duration {duration} s is shorter than one step of {dt} s")
    s0 = time.perf_counter()
    run(steps)
    wall = time.perf_counter() - s0

    pos_err = float(np.linalg.norm(state["x"] - x0))
    if not math.isfinite(pos_err) or pos_err > 0.05:
        raise RuntimeError(f"RotorPy hover diverged: position error {pos_err} m after {t:.3f} s")
    if not all(np.all(np.isfinite(meas[k])) for k in ("accel", "gyro")):
        raise RuntimeError("RotorPy IMU produced non-finite measurements")
    sim = steps * dt
    return {
        "rtf": sim / wall,
        "us_per_step": wall / steps * 1e6,
        "sim_time_s": sim,
        "wall_time_s": wall,
        "steps": steps,
        "warmup_steps": warmup_steps,
        "warmup_us_per_step": warm_s / warmup_steps * 1e6 if warmup_steps else None,
        "setup_s": setup_s,
        "final_position_error_m": pos_err,
        "rotorpy_version": version,
    }


@probe(ROTORPY_SIMULATE, params={"duration": 3.0, "dt": 0.001, "seed": 0},
       quick={"duration": 0.3},
       description="RotorPy 3.0.0 simulate() at 1 kHz, hover, with its IMU and default extras")
def rotorpy_simulate(duration: float, dt: float, seed: int) -> dict:
    """RotorPy's own ``simulate()`` (history lists, mocap, null estimator, both IMU calls)."""
    np, vehicle, controller, trajectory, imu, state, x0, version = _build(dt)
    from rotorpy.estimators.nullestimator import NullEstimator
    from rotorpy.sensors.external_mocap import MotionCapture
    from rotorpy.simulate import ExitStatus, simulate
    from rotorpy.wind.default_winds import NoWind
    from rotorpy.world import World

    # The same defaults rotorpy.environments.Environment fills in (without importing
    # matplotlib through it).
    mocap_params = {
        "pos_noise_density": 0.0005 * np.ones((3,)), "vel_noise_density": 0.0010 * np.ones((3,)),
        "att_noise_density": 0.0005 * np.ones((3,)), "rate_noise_density": 0.0005 * np.ones((3,)),
        "vel_artifact_max": 5, "vel_artifact_prob": 0.001,
        "rate_artifact_max": 1, "rate_artifact_prob": 0.0002,
    }
    mocap = MotionCapture(sampling_rate=round(1.0 / dt), mocap_params=mocap_params, with_artifacts=False)
    world = World.empty((-3, 3, -3, 3, -3, 3))
    np.random.seed(seed)
    s0 = time.perf_counter()
    out = simulate(world, vehicle.initial_state, vehicle, controller, trajectory, NoWind(), imu,
                   mocap, NullEstimator(), duration, dt, 0.25, False, terminate=False)
    wall = time.perf_counter() - s0
    times, states, exit_status = out[0], out[1], out[8]
    if exit_status is not ExitStatus.TIMEOUT:
        raise RuntimeError(f"RotorPy simulate() ended with {exit_status}")
    sim = float(times[-1])
    pos_err = float(np.linalg.norm(states["x"][-1] - x0))
    return {
        "rtf": sim / wall,
        "us_per_step": wall / (len(times) - 1) * 1e6,
        "sim_time_s": sim,
        "wall_time_s": wall,
        "steps": len(times) - 1,
        "final_position_error_m": pos_err,
        "rotorpy_version": version,
    }


@benchmark("rotorpy-reference", probes=(ROTORPY_BARE, ROTORPY_SIMULATE),
           description="RotorPy 3.0.0 speed at 1 kHz with its IMU (the reference of rig-core)")
def rotorpy_reference(stats: dict[str, ProbeStats]) -> list[Metric]:
    bare, full = stats[ROTORPY_BARE], stats[ROTORPY_SIMULATE]
    return [
        bare.metric("rtf", "bare loop real-time factor", "x real time",
                    note=f"the project's performance notes recorded ~{NOTED_RTF}x (2026-11-22); "
                         "ratios use only the figure measured in this run"),
        bare.metric("us_per_step", "bare loop time per 1 ms step", "us"),
        full.metric("rtf", "simulate() real-time factor", "x real time"),
        paired_ratio_metric(bare, "rtf", full, "rtf", "bare loop speed-up over simulate()"),
    ]
