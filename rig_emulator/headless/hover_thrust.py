"""The normalised collective thrust that hovers (SET_ATTITUDE_TARGET.thrust, PX4's MPC_THR_HOVER).

An attitude or body-rate set-point carries a collective thrust in [0, 1]; the served rig reads
it as a fraction of the largest collective thrust the four motors give
(:meth:`~rig_emulator.simulation.live.LiveRig.collective_thrust_from_fraction`: u1 = thrust x 4 x
the per-motor limit, 28.0 N on ``hilms``). The controllers turn u1 into motor voltages through
their Eq. 40 inverse. On the ideal plant Eq. 40 is the motors' true curve, so the fraction that
hovers is m g / u1_max = 0.781. On the hardware rig the true thrust differs from Eq. 40 (the
convex curve, the per-motor gains, the -50 gr.F running bias, ESC quantisation,
``presets/hardware/hilms.toml``) and the firmware's load-cell thrust loop corrects the commands
slowly (``motors.thrust_loop_time_constant``, 200 s): the fraction that hovers depends on how
long the rig has flown.

* :func:`hover_fraction`: the fraction whose motor commands, through the firmware's Eq. 40
  inverse with the thrust loop's present correction, make the motors' true thrust carry the
  weight, level (the thrust chain solved in its steady state, no flight; what a ground station
  reads as MPC_THR_HOVER).
* :func:`measure_hover_fraction`: flies it (``rig-emulator hover-thrust``): hold 2 m in position
  mode for ``settle_s``, then fly level attitude set-points at a thrust for ``window_s`` and fit
  the altitude the rig reports (its onboard position) with a parabola; the fraction of zero
  vertical acceleration is found by the secant rule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

ALTITUDE_M = 2.0  # where the measurement hovers before the thrust is applied
SAMPLE_S = 0.05  # altitude sampling of the measurement


def _chain_thrust(rig, fraction: float) -> float:
    """Total true thrust (N) of the four motors, level, for a collective thrust ``fraction``: the
    firmware's Eq. 40 inverse (with the thrust loop's present correction when it runs), the ESC's
    quantisation and dead-band, the motors' true curve (no lag: the steady state)."""
    from rig_emulator.control.controller import CS_THRUST_CORR
    from rig_emulator.physics.hardware import motor_thrust
    from rig_emulator.physics.motors import voltage_for_thrust

    sim = rig.sim
    pp, cp = sim.pp, sim.cp
    hw = pp.hw._replace(curve_memo=np.full((4, 2), np.nan))  # the running rig's memo stays untouched
    loop = cp.thrust_loop_rate > 0.0 and sim.sensing.params.simulate
    f_des = fraction * rig.max_collective_thrust() / 4.0
    total = 0.0
    for i in range(4):
        corr = float(sim.cstate[CS_THRUST_CORR + i]) if loop and f_des > 0.0 else 0.0
        v = voltage_for_thrust.py_func(f_des + corr, cp.k_v, cp.v_max) if f_des > 0.0 else 0.0
        if hw.quantum > 0.0:
            v = math.floor(v / hw.quantum + 0.5) * hw.quantum
        if v < hw.deadband:
            v = 0.0
        total += motor_thrust.py_func(v, i, pp.k_v, pp.f_ceiling, float(pp.thrust_efficiency[i]), hw)
    return total


def hover_fraction(rig) -> float:
    """The collective thrust fraction in [0, 1] whose steady true thrust equals the weight m g
    (bisection on :func:`_chain_thrust`; 1.0 when even full thrust does not carry it)."""
    weight = rig.sim.pp.mass * rig.sim.pp.g
    lo, hi = 0.0, 1.0
    if _chain_thrust(rig, hi) < weight:
        return 1.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if _chain_thrust(rig, mid) < weight:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class ThrustTrial:
    fraction: float
    accel_m_s2: float  # vertical acceleration of the onboard position, parabola fit over the window
    climb_m: float  # onboard altitude change over the window
    climb_sim_state_m: float  # the physics vehicle's (SIM_STATE)


@dataclass(frozen=True)
class HoverMeasurement:
    airframe: str
    seed: int
    settle_s: float
    window_s: float
    nominal: float  # m g / u1_max, the fraction that hovers when the motors follow Eq. 40
    served: float  # hover_fraction() of the rig when the thrust was applied (MPC_THR_HOVER then)
    measured: float  # secant root of the trials' acceleration
    trials: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"airframe": self.airframe, "seed": self.seed, "settle_s": self.settle_s, "window_s": self.window_s,
                "nominal": self.nominal, "served": self.served, "measured": self.measured,
                "trials": [t.__dict__ for t in self.trials]}


def _rig(airframe: str, seed: int, overrides: dict):
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.live import LiveRig

    flat = dict(overrides)
    flat["sim.seed"] = seed
    rig = LiveRig(load_config(airframe=airframe, overrides=flat))
    rig.warm_up()
    return rig


def _advance(rig, seconds: float) -> None:
    n = int(round(seconds / rig.dt))
    while n > 0:
        k = min(n, rig.chunk_steps_max)
        rig.step(k)
        n -= k


def settle(rig, settle_s: float) -> float:
    """Arm, climb to :data:`ALTITUDE_M` in position mode and hold it ``settle_s``; returns the heading."""
    psi = math.radians(rig.cfg["initial.euler_deg"][2])
    rig.arm(True)
    rig.set_position_target([0.0, 0.0, ALTITUDE_M], yaw=psi)
    _advance(rig, settle_s)
    return psi


def fly_thrust(rig, psi: float, fraction: float, window_s: float) -> ThrustTrial:
    """Level attitude set-points at collective thrust ``fraction`` for ``window_s`` from now."""
    rig.set_attitude_target(0.0, 0.0, psi, thrust_fraction=fraction)
    t, z, z_true = [], [], []
    steps = max(1, int(round(SAMPLE_S / rig.dt)))
    t0 = rig.time_s
    for _ in range(int(round(window_s / SAMPLE_S)) + 1):
        t.append(rig.time_s - t0)
        z.append(float(rig.position_now()[2]))
        z_true.append(float(rig.sim.x[2]))
        _advance(rig, steps * rig.dt)
    accel = 2.0 * float(np.polyfit(np.array(t), np.array(z), 2)[0])
    return ThrustTrial(fraction=fraction, accel_m_s2=accel, climb_m=z[-1] - z[0], climb_sim_state_m=z_true[-1] - z_true[0])


def measure_hover_fraction(airframe: str = "hilms", seed: int = 0, overrides: dict | None = None,
                           settle_s: float = 20.0, window_s: float = 5.0, tol_m_s2: float = 0.005,
                           max_trials: int = 6) -> HoverMeasurement:
    """Fly the rig at thrusts found by the secant rule until its onboard altitude's acceleration is
    within ``tol_m_s2`` of zero; each trial is a fresh rig with the same seed, settled alike."""
    overrides = overrides or {}

    def trial(fraction):
        rig = _rig(airframe, seed, overrides)
        psi = settle(rig, settle_s)
        return fly_thrust(rig, psi, fraction, window_s)

    rig = _rig(airframe, seed, overrides)
    nominal = rig.hover_thrust_fraction()
    psi = settle(rig, settle_s)
    served = hover_fraction(rig)
    trials = [fly_thrust(rig, psi, served, window_s)]
    if abs(trials[0].accel_m_s2) > tol_m_s2:
        other = served + (0.01 if trials[0].accel_m_s2 < 0.0 else -0.01)
        trials.append(trial(other))
        while len(trials) < max_trials:
            a, b = trials[-2], trials[-1]
            if b.accel_m_s2 == a.accel_m_s2:
                break
            f = b.fraction - b.accel_m_s2 * (b.fraction - a.fraction) / (b.accel_m_s2 - a.accel_m_s2)
            f = min(max(f, 0.0), 1.0)
            trials.append(trial(f))
            if abs(trials[-1].accel_m_s2) <= tol_m_s2:
                break
    best = min(trials, key=lambda tr: abs(tr.accel_m_s2))
    return HoverMeasurement(airframe=airframe, seed=seed, settle_s=settle_s, window_s=window_s, nominal=nominal,
                            served=served, measured=best.fraction, trials=trials)


def format_measurement(m: HoverMeasurement) -> str:
    lines = [f"{m.airframe} (seed {m.seed}, {m.settle_s:g} s hold at {ALTITUDE_M:g} m, then {m.window_s:g} s level "
             f"at each thrust): hovers at {m.measured:.4f} (MPC_THR_HOVER served {m.served:.4f}; m g / u1_max "
             f"{m.nominal:.4f})"]
    for tr in m.trials:
        lines.append(f"  thrust {tr.fraction:.4f}: vertical acceleration {tr.accel_m_s2:+.4f} m/s^2, climb "
                     f"{tr.climb_m:+.3f} m (SIM_STATE {tr.climb_sim_state_m:+.3f} m) in {m.window_s:g} s")
    return "\n".join(lines)
