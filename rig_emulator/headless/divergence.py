"""How far the rig's onboard virtual position and the physics vehicle (SIM_STATE) part.

The HILMS cannot translate. Its onboard computer integrates a virtual vehicle (Eq. 1) from the
filtered load-cell thrusts and the estimated attitude: that is the position the controllers fly
and the rig reports (LOCAL_POSITION_NED, GLOBAL_POSITION_INT). The emulator integrates a second,
free-flying vehicle from the rig's true thrusts and true attitude (the physics state, served as
SIM_STATE); the real rig has no such thing. The two integrate the same Eq. 1 from different
inputs (the load cells' calibration, noise and filter lag, the attitude estimate's error), and a
small force error integrated twice grows as t^2: they part by metres within a minute
(docs/explanation/sim-state.md).

* :func:`divergence_stats`: the figures of a recorded run (``pos`` minus ``pos_true``).
* :func:`onboard_minus_physics`: the same vector on a running rig, now.
* :class:`DivergenceWatch`: the served rig's once-per-episode report.
* ``rig-emulator divergence``: the figures for scenarios, seeds and plants (:func:`main_rows`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

GROUND_Z_M = 1e-9  # a logged altitude at or below this is on the virtual ground


@dataclass(frozen=True)
class DivergenceStats:
    """Onboard minus physics position over one run (NED, metres, as a ground station reads
    LOCAL_POSITION_NED against SIM_STATE)."""

    max_m: float  # largest distance
    rms_m: float  # root mean square of the distance over the run
    first_over_s: float  # first time the distance exceeds the threshold (NaN: never)
    at: dict  # time (s) -> (dN, dE, dD) at that time
    slid_onboard_m: float  # horizontal path of the onboard vehicle while it stood on the ground
    slid_physics_m: float  # the same for the physics vehicle
    grounded_physics_s: float  # time the physics vehicle spent on the ground


def _ground_path(t: np.ndarray, pos: np.ndarray) -> tuple[float, float]:
    """Horizontal path (m) between consecutive log rows both on the ground, and time on it (s)."""
    on = pos[:, 2] <= GROUND_Z_M
    both = on[1:] & on[:-1]
    step = np.hypot(np.diff(pos[:, 0]), np.diff(pos[:, 1]))
    return float(step[both].sum()), float(np.diff(t)[both].sum())


def divergence_stats(series: dict, threshold_m: float, times=(30.0, 60.0)) -> DivergenceStats:
    """The figures of a recorded series (``t``, ``pos``, ``pos_true`` in world ENU); ``times``
    within the run give the vector at the log row nearest each."""
    t = series["t"]
    d = series["pos"] - series["pos_true"]
    dist = np.linalg.norm(d, axis=1)
    over = np.nonzero(dist > threshold_m)[0]
    at = {}
    for when in times:
        if t[0] <= when <= t[-1] + (t[-1] - t[-2] if t.size > 1 else 0.0) + 1e-9:
            i = int(np.argmin(np.abs(t - when)))
            at[float(when)] = (float(d[i, 1]), float(d[i, 0]), float(-d[i, 2]))  # ENU -> NED
    slid_on, _ = _ground_path(t, series["pos"])
    slid_ph, grounded = _ground_path(t, series["pos_true"])
    return DivergenceStats(max_m=float(dist.max()), rms_m=float(np.sqrt(np.mean(dist ** 2))),
                           first_over_s=float(t[over[0]]) if over.size else math.nan, at=at,
                           slid_onboard_m=slid_on, slid_physics_m=slid_ph, grounded_physics_s=grounded)


def onboard_minus_physics(rig) -> tuple[float, float, float] | None:
    """Onboard virtual position minus the physics vehicle's, world ENU (m), of a running
    :class:`~rig_emulator.simulation.live.LiveRig` now; None when the rig flies on the physics
    (sensor models off: there is no onboard position apart from it)."""
    sim = rig.sim
    sp, ss = sim.sensing.params, sim.sensing.state
    if not sp.estimated:
        return None
    o, x = ss.onboard.item, sim.x.item
    return o(0) - x(0), o(1) - x(1), o(2) - x(2)


class DivergenceWatch:
    """Says once when the onboard position and the physics vehicle part by more than
    ``estimation.divergence_warning_m``; the next report waits until they came back within half
    of it (a new episode: e.g. after a reboot). Polled after every chunk of the served rig."""

    def __init__(self):
        self.reporting = False  # over the threshold and reported
        self.reports = 0

    def poll(self, rig) -> str | None:
        """The text to report now, or None."""
        threshold = rig.cfg["estimation.divergence_warning_m"]
        if threshold <= 0.0:
            return None
        d = onboard_minus_physics(rig)
        if d is None:
            return None
        dist = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        if self.reporting:
            if dist < 0.5 * threshold:
                self.reporting = False
            return None
        if dist <= threshold:
            return None
        self.reporting = True
        self.reports += 1
        return (f"onboard position and SIM_STATE {dist:.1f} m apart (N {d[1]:+.1f} E {d[0]:+.1f} D {-d[2]:+.1f}); "
                "the rig flies the onboard one")


def run_stats(scenario: str, airframe: str, strategy: str, seed: int, duration: float | None,
              overrides: dict, threshold_m: float | None, times) -> tuple[DivergenceStats, float, float]:
    """Run ``scenario`` headless on ``airframe``; returns the figures, the threshold used and the
    simulated seconds."""
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.run import Simulation

    flat = dict(overrides)
    flat["control.strategy"] = strategy
    flat["sim.seed"] = seed
    if duration is not None:
        flat["sim.duration"] = float(duration)
    cfg = load_config(airframe=airframe, scenario=scenario, overrides=flat)
    threshold = cfg["estimation.divergence_warning_m"] if threshold_m is None else threshold_m
    result = Simulation(cfg).run()
    return divergence_stats(result.series, threshold, times), threshold, float(cfg["sim.duration"])


def markdown_table(rows, times=(30.0, 60.0)) -> str:
    """The runs as the table docs/explanation/sim-state.md includes: ``rows`` of (scenario, airframe, seed,
    stats, threshold, ...) as ``rig-emulator divergence`` collects them; a vector column per time in
    ``times`` (empty where the run ended before it)."""
    thresholds = {r[4] for r in rows}
    over = f"over {next(iter(thresholds)):g} m from" if len(thresholds) == 1 else "over the threshold from"
    head = ["scenario", "plant"] + (["seed"] if len({r[2] for r in rows}) > 1 else []) + [
        "max", "rms", over] + [f"at {t:g} s (N, E, D)" for t in times]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for scenario, airframe, seed, st, *_ in rows:
        cells = [scenario, airframe] + ([str(seed)] if "seed" in head else []) + [
            f"{st.max_m:.2f} m", f"{st.rms_m:.2f} m",
            "never" if math.isnan(st.first_over_s) else f"{st.first_over_s:.1f} s"]
        cells += [", ".join(f"{x:+.2f}" for x in st.at[t]) if t in st.at else "" for t in times]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def format_row(scenario: str, airframe: str, seed: int, stats: DivergenceStats, threshold: float) -> str:
    first = "never" if math.isnan(stats.first_over_s) else f"{stats.first_over_s:.1f} s"
    at = "  ".join(f"t={t:g} s: N {n:+.2f} E {e:+.2f} D {d:+.2f}" for t, (n, e, d) in stats.at.items())
    return (f"{scenario:13s} {airframe:12s} {seed:4d}  max {stats.max_m:6.2f} m  rms {stats.rms_m:6.2f} m  "
            f"> {threshold:g} m at {first:8s} slid on ground: onboard {stats.slid_onboard_m:.3f} m, "
            f"SIM_STATE {stats.slid_physics_m:.3f} m ({stats.grounded_physics_s:.1f} s on it)  {at}")
