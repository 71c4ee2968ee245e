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

* :class:`HoverThrustEstimate`: what a ground station reads as MPC_THR_HOVER on the served rig.
  Like PX4's hover thrust estimator (``MPC_USE_HTE``), it learns the value in flight: the mean
  collective thrust the position controller commands while the rig holds its altitude (armed,
  position control, above :data:`AIRBORNE_M`, climbing or sinking slower than
  :data:`STEADY_M_S`), averaged over :data:`ESTIMATE_TAU_S`. In a steady hover that mean is by
  definition what carries the weight, the motors' activity included: with the convex true
  curve the attitude law's differential commands raise the mean thrust (the ``hilms`` SMC's
  chattering: about 0.003 of the fraction). Before the rig has flown it is
  :func:`hover_fraction`.
* :func:`hover_fraction`: the fraction whose motor commands, through the firmware's Eq. 40
  inverse with the thrust loop's present correction, make the motors' true thrust carry the
  weight, level and steady (the thrust chain solved, no flight).
* :func:`measure_hover_fraction`: flies it (``rig-emulator hover-thrust``): hold 2 m in position
  mode for ``settle_s``, then fly level attitude set-points at a thrust for ``window_s`` and fit
  the altitude the rig reports (its onboard position) with a parabola; the fraction of zero
  vertical acceleration is the root of a straight line fitted through trials around the served
  value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rig_emulator.simulation import log_layout as L

ALTITUDE_M = 2.0  # where the measurement hovers before the thrust is applied
SAMPLE_S = 0.05  # altitude sampling of the measurement
FLOOR_M = 0.3  # a trial that sinks to this onboard altitude ends there
AIRBORNE_M = 0.5  # the estimate learns above this onboard altitude ...
STEADY_M_S = 0.3  # ... while the vertical speed is under this
ESTIMATE_TAU_S = 5.0  # time constant of the estimate's average (s of flight)


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


class HoverThrustEstimate:
    """MPC_THR_HOVER of the served rig: learnt in steady position-controlled flight from the
    commanded collective thrust (the rig's log rows of each chunk), else :func:`hover_fraction`."""

    def __init__(self):
        self.estimate: float | None = None
        self.learnt_s = 0.0  # flight time the estimate has learnt from

    def update(self, rows: np.ndarray, rig) -> None:
        """Learn from the log rows a chunk recorded (:meth:`LiveRig.step`'s return)."""
        if rows.shape[0] == 0 or not rig.sim.armed:
            return
        dt = rig.sim.log_div * rig.dt
        u_max = 4.0 * rig.sim.cp.f_max  # LiveRig.max_collective_thrust
        item = rows.item  # a row or two a chunk: single items are cheaper than array masks
        for i in range(rows.shape[0]):
            if (item(i, L.MODE) != 0.0 or item(i, L.POS + 2) <= AIRBORNE_M or abs(item(i, L.VEL + 2)) >= STEADY_M_S
                    or item(i, L.FAILSAFE) != 0.0):
                continue
            f = item(i, L.U) / u_max
            # the mean of everything learnt for the first ESTIMATE_TAU_S, then an exponential average
            w = dt / (self.learnt_s + dt) if self.learnt_s < ESTIMATE_TAU_S else dt / ESTIMATE_TAU_S
            self.estimate = f if self.estimate is None else self.estimate + w * (f - self.estimate)
            self.learnt_s += dt

    def value(self, rig) -> float:
        return hover_fraction(rig) if self.estimate is None else min(max(self.estimate, 0.0), 1.0)


@dataclass(frozen=True)
class ThrustTrial:
    fraction: float
    accel_m_s2: float  # vertical acceleration of the onboard position, parabola fit over the window
    climb_m: float  # onboard altitude change over the window
    climb_sim_state_m: float  # the physics vehicle's (SIM_STATE)
    duration_s: float  # how long it flew at the thrust (less than the window when it sank to FLOOR_M)


@dataclass(frozen=True)
class HoverMeasurement:
    airframe: str
    seed: int
    settle_s: float
    window_s: float
    nominal: float  # m g / u1_max, the fraction that hovers when the motors follow Eq. 40
    served: float  # MPC_THR_HOVER when the thrust was applied (HoverThrustEstimate learnt over the hold)
    steady: float  # hover_fraction() then: the thrust chain's steady solution
    measured: float  # root of the line fitted to the trials' acceleration against the thrust
    trials: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"airframe": self.airframe, "seed": self.seed, "settle_s": self.settle_s, "window_s": self.window_s,
                "nominal": self.nominal, "served": self.served, "steady": self.steady, "measured": self.measured,
                "trials": [t.__dict__ for t in self.trials]}


def _rig(airframe: str, seed: int, overrides: dict):
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.live import LiveRig

    flat = dict(overrides)
    flat["sim.seed"] = seed
    rig = LiveRig(load_config(airframe=airframe, overrides=flat))
    rig.warm_up()
    return rig


def _advance(rig, seconds: float, estimate: HoverThrustEstimate | None = None) -> None:
    n = int(round(seconds / rig.dt))
    while n > 0:
        k = min(n, rig.chunk_steps_max)
        rows = rig.step(k)
        if estimate is not None:
            estimate.update(rows, rig)
        n -= k


def settle(rig, settle_s: float, estimate: HoverThrustEstimate | None = None) -> float:
    """Arm, climb to :data:`ALTITUDE_M` in position mode and hold it ``settle_s`` (``estimate``
    learning meanwhile, as the served rig's does); returns the heading."""
    psi = math.radians(rig.cfg["initial.euler_deg"][2])
    rig.arm(True)
    rig.set_position_target([0.0, 0.0, ALTITUDE_M], yaw=psi)
    _advance(rig, settle_s, estimate)
    return psi


def fly_thrust(rig, psi: float, fraction: float, window_s: float) -> ThrustTrial:
    """Level attitude set-points at collective thrust ``fraction`` for ``window_s`` from now; the
    trial ends early when the onboard altitude comes down to :data:`FLOOR_M` (the fit would read
    the ground)."""
    rig.set_attitude_target(0.0, 0.0, psi, thrust_fraction=fraction)
    t, z, z_true = [], [], []
    steps = max(1, int(round(SAMPLE_S / rig.dt)))
    t0 = rig.time_s
    for _ in range(int(round(window_s / SAMPLE_S)) + 1):
        t.append(rig.time_s - t0)
        z.append(float(rig.position_now()[2]))
        z_true.append(float(rig.sim.x[2]))
        if z[-1] < FLOOR_M:
            break
        _advance(rig, steps * rig.dt)
    accel = 2.0 * float(np.polyfit(np.array(t), np.array(z), 2)[0]) if len(t) >= 3 else math.nan
    return ThrustTrial(fraction=fraction, accel_m_s2=accel, climb_m=z[-1] - z[0], climb_sim_state_m=z_true[-1] - z_true[0],
                       duration_s=t[-1])


def measure_hover_fraction(airframe: str = "hilms", seed: int = 0, overrides: dict | None = None,
                           settle_s: float = 20.0, window_s: float = 5.0, step: float = 0.01) -> HoverMeasurement:
    """Fly the rig at the served hover fraction and ``step`` either side of it, fit the onboard
    altitude's vertical acceleration against the thrust with a straight line, fly its root to
    check it, and return the root of the line through all four (trials that sank to the floor
    are left out of the fit). Each trial is a fresh rig with the same seed, settled alike."""
    overrides = overrides or {}
    rig = _rig(airframe, seed, overrides)
    nominal = rig.hover_thrust_fraction()
    estimate = HoverThrustEstimate()
    psi = settle(rig, settle_s, estimate)
    served = estimate.value(rig)
    steady = hover_fraction(rig)
    trials = [fly_thrust(rig, psi, served, window_s)]
    trials += fly_fractions(airframe, (served - step, served + step), seed, overrides, settle_s, window_s)

    def root(ts):
        ok = [tr for tr in ts if tr.duration_s >= window_s - 1e-9 and math.isfinite(tr.accel_m_s2)]
        if len(ok) < 2:
            return served
        slope, icpt = np.polyfit([tr.fraction for tr in ok], [tr.accel_m_s2 for tr in ok], 1)
        return float(min(max(-icpt / slope, 0.0), 1.0)) if slope > 0.0 else served

    trials += fly_fractions(airframe, (root(trials),), seed, overrides, settle_s, window_s)
    return HoverMeasurement(airframe=airframe, seed=seed, settle_s=settle_s, window_s=window_s, nominal=nominal,
                            served=served, steady=steady, measured=root(trials), trials=trials)


def fly_fractions(airframe: str, fractions, seed: int = 0, overrides: dict | None = None, settle_s: float = 20.0,
                  window_s: float = 5.0) -> list[ThrustTrial]:
    """One trial per thrust in ``fractions`` (each a fresh rig, settled as in :func:`measure_hover_fraction`)."""
    out = []
    for fraction in fractions:
        rig = _rig(airframe, seed, overrides or {})
        psi = settle(rig, settle_s)
        out.append(fly_thrust(rig, psi, fraction, window_s))
    return out


def format_measurement(m: HoverMeasurement) -> str:
    lines = [f"{m.airframe} (seed {m.seed}, {m.settle_s:g} s hold at {ALTITUDE_M:g} m, then {m.window_s:g} s level "
             f"at each thrust): hovers at {m.measured:.4f}; MPC_THR_HOVER served {m.served:.4f}; thrust chain "
             f"steady {m.steady:.4f}; m g / u1_max {m.nominal:.4f}"]
    lines.extend(format_trial(tr, m.window_s) for tr in m.trials)
    return "\n".join(lines)


def format_trial(tr: ThrustTrial, window_s: float) -> str:
    return (f"  thrust {tr.fraction:.4f}: vertical acceleration {tr.accel_m_s2:+.4f} m/s^2, climb {tr.climb_m:+.3f} m "
            f"(SIM_STATE {tr.climb_sim_state_m:+.3f} m) in {tr.duration_s:.2f} s"
            + (f" (sank to {FLOOR_M:g} m: trial ended)" if tr.duration_s < window_s - 1e-9 else ""))
