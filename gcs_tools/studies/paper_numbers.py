"""The paper's 18 numbers (Table 4, Table 6, Fig. 19) on ``hilms`` over a scan of one setting, mean
over seeds 0-2 (docs/explanation/readings.md, "The position FLC's rate input", "The heading and the
motors' magnetic field" and "The delay and the joint's friction"; the ``point`` study in
docs/explanation/paper-fit.md).

    python -m gcs_tools.studies paper-numbers rate-share [--values 0.2,0.25,...] [--workers N]
    python -m gcs_tools.studies paper-numbers yaw [--values 0.005,0.03,0.06] [--set KEY=VALUE ...]
    python -m gcs_tools.studies paper-numbers delay [--values 0.006,0.01,...] [--set KEY=VALUE ...]
    python -m gcs_tools.studies paper-numbers point [--set KEY=VALUE ...]     # one setting, all 18 numbers
    python -m gcs_tools.studies paper-numbers point --markdown FILE   # also write the tables as a docs page
    python -m gcs_tools.studies paper-numbers priors [--values C:B,...]  # the text's priors against the numbers

Every point runs the job list of ``rig-gcs identify --paper`` (the reproduction's own sweep, helix
and rectangle runs: 29 headless runs a seed) with the setting as an override, so its numbers are the
ones a fit and ``rig-gcs reproduce`` compute. ``rate-share`` prints, per value of
``flc.position_rate_share``, the eight position numbers the key governs (Table 6 X / Y / Z of both
strategies, Fig. 19 X / Y), their rms log error against the paper and how many are within a factor
2; ``yaw`` prints both strategies' Table 6 psi per random yaw torque (``disturbance.torque_noise``'s
third element; roll and pitch keep the preset's); ``delay`` prints, per sensing-to-actuation delay
(``control.actuation_delay``), the attitude numbers, each attitude law's Table 4 / Table 6 ratio,
the 18 numbers' summary and how many of the 12 claims ``rig-gcs identify --claims`` fits hold
(its runs add the shock and extra-mass experiments: 39 a seed). ``priors`` (docs/explanation/paper-fit.md,
"What the paper's numbers demand against its text") moves the two values the paper's text bounds,
the roll and pitch Coulomb friction and the thrust bias (``--values COULOMB:BIAS,...``), on the short
job list (``--paper-variant short``), and prints the 18 numbers' summary, Table 6's altitude and FLC
attitude errors and the fit's cost without and with the paper's priors (``paper_priors.toml``).
"""

from __future__ import annotations

import argparse
import fnmatch
import math

import numpy as np

from gcs_tools.identify.paper import FACTOR_2, PaperProblem, load_data, log_residual, select_targets
from gcs_tools.identify.problem import Base
from gcs_tools.studies.page import Page
from rig_emulator.config.loader import load_config, parse_override
from rig_emulator.sweep import run_jobs

SEEDS = (0, 1, 2)  # consecutive: PaperProblem's seeds .. seeds + n - 1
RATE_SHARES = (0.2, 0.25, 0.3, 0.35, 0.4, 0.42, 0.45, 0.48, 0.5, 0.55, 0.65)
YAW_TORQUES = (0.005, 0.03, 0.06)
DELAYS = (0.006, 0.008, 0.010, 0.012, 0.013, 0.014, 0.016)
#: (roll / pitch Coulomb friction N m, thrust bias gr.F): the shipped preset, each moved towards the
#: paper's text alone, then both at the priors' means
PRIOR_POINTS = ((0.05, -50.0), (0.01, -50.0), (0.0, -50.0), (0.05, -25.0), (0.05, 0.0), (0.0, 0.0))
# Numbers whose ratios to each other no effect of the preset moves much (measured: the delay, the random
# torque and the Coulomb friction move both tables of an attitude law together, "The actuation delay";
# the rate share moves the helix's and the rectangle's X / Y together, "The position FLC's rate share"):
# only each group's common level is free.
LEVEL_GROUPS = {
    "SMC attitude (Table 4 SMC, Table 6 SMC-FLC phi / theta)":
        ("table4.smc.*", "table6.smc-flc.phi_deg", "table6.smc-flc.theta_deg"),
    "FLC attitude (Table 4 FLC, Table 6 FLC phi / theta)": ("table4.flc.*", "table6.flc.phi_deg", "table6.flc.theta_deg"),
    "X / Y (Table 6, Fig. 19)": ("table6.*.x_m", "table6.*.y_m", "fig19.*"),
    "Z (Table 6)": ("table6.*.z_m",),
    "psi (Table 6)": ("table6.*.psi_deg",),
}


def numbers(overrides: list, workers: int, claims: bool = False, variant: str = "full") -> tuple[dict, list]:
    """The metrics of every target (and with ``claims`` of the 12 claims ``rig-gcs identify
    --claims`` fits), mean over :data:`SEEDS`, and the targets (``variant``: PaperProblem's job list)."""
    problem = PaperProblem(Base(airframe="hilms", overrides=tuple(overrides)), seed=SEEDS[0], seeds=len(SEEDS),
                           claims=claims, variant=variant)
    return problem.metrics(run_jobs(problem.jobs([], []), workers=workers)), problem.targets


def _claims_held(mean: dict) -> tuple[int, int]:
    """How many of the claims ``rig-gcs identify --claims`` fits hold on these metrics, of how many."""
    _, claims = load_data()
    return sum(c.holds(mean[c.metric]) for c in claims), len(claims)


def _logs(mean: dict, targets, names) -> list[float]:
    paper = {t.metric: t.value for t in targets}
    return [log_residual(mean[n], paper[n]) for n in names]


def _rms(values) -> float:
    return math.sqrt(np.mean(np.square(values)))


def _within(logs) -> int:
    return sum(abs(x) <= FACTOR_2 for x in logs)


def rate_share(values, base: list, workers: int, out: Page) -> None:
    out.print("| rate share | Table 6 FLC X / Y / Z (m) | Table 6 SMC-FLC X / Y / Z (m) | Fig. 19 X / Y (m) "
          "| rms log error, 8 position numbers | within x2 (of 8) | Table 6 within x2 (of 12) "
          "| Table 6 FLC / SMC-FLC psi (deg) |")
    out.print("|---|---|---|---|---|---|---|---|")
    for v in values:
        mean, targets = numbers(base + [("flc.position_rate_share", v)], workers)
        position = [t.metric for t in select_targets(targets, "position")]  # Table 6 X / Y / Z, Fig. 19
        pos = _logs(mean, targets, position)
        t6 = _logs(mean, targets, [t.metric for t in targets if t.metric.startswith("table6.")])
        f = [mean[n] for n in position]
        out.print(f"| {v:g} | {f[0]:.3f} / {f[1]:.3f} / {f[2]:.3f} | {f[3]:.3f} / {f[4]:.3f} / {f[5]:.3f} "
              f"| {f[6]:.3f} / {f[7]:.3f} | {_rms(pos):.3f} | {_within(pos)} "
              f"| {_within(t6)} | {mean['table6.flc.psi_deg']:.3f} / {mean['table6.smc-flc.psi_deg']:.3f} |")


def yaw(values, base: list, workers: int, out: Page) -> None:
    cfg = load_config("hilms", overrides=dict(base))
    roll_pitch = list(cfg["disturbance.torque_noise"])[:2]
    out.print("| yaw torque std (N m) | FLC psi (deg) | SMC-FLC psi (deg) | SMC-FLC / FLC |")
    out.print("|---|---|---|---|")
    for v in values:
        mean, _ = numbers(base + [("disturbance.torque_noise", roll_pitch + [v])], workers)
        a, b = mean["table6.flc.psi_deg"], mean["table6.smc-flc.psi_deg"]
        out.print(f"| {v:g} | {a:.3f} | {b:.3f} | {b / a:.2f} |")


def delay(values, base: list, workers: int, out: Page) -> None:
    """Per sensing-to-actuation delay: the paper's attitude numbers, the ratio of each attitude
    law's error on the harmonic sweep (Table 4) to its error on the helix (Table 6; the SMC's
    inner loop there is SMC-FLC's), all 18 numbers and the claims."""
    out.print("| delay (ms) | Table 4 SMC phi / theta | Table 4 FLC phi / theta | Table 6 FLC phi / theta / psi "
          "| Table 6 SMC-FLC phi / theta / psi | SMC Table 4 / Table 6 | FLC Table 4 / Table 6 "
          "| within x2 (of 18) | rms log error | Table 6 within x2 (of 12) | claims held (of the fitted) |")
    out.print("|---|---|---|---|---|---|---|---|---|---|---|")
    for v in values:
        g, targets = numbers(base + [("control.actuation_delay", v)], workers, claims=True)
        logs = _logs(g, targets, [t.metric for t in targets])
        t6 = _logs(g, targets, [t.metric for t in targets if t.metric.startswith("table6.")])
        held, n = _claims_held(g)
        out.print(f"| {v * 1e3:g} | {g['table4.smc.phi_deg']:.2f} / {g['table4.smc.theta_deg']:.2f} "
              f"| {g['table4.flc.phi_deg']:.2f} / {g['table4.flc.theta_deg']:.2f} "
              f"| {g['table6.flc.phi_deg']:.2f} / {g['table6.flc.theta_deg']:.2f} / {g['table6.flc.psi_deg']:.2f} "
              f"| {g['table6.smc-flc.phi_deg']:.2f} / {g['table6.smc-flc.theta_deg']:.2f} / "
              f"{g['table6.smc-flc.psi_deg']:.2f} | {_table4_over_table6(g, 'smc'):.2f} "
              f"| {_table4_over_table6(g, 'flc'):.2f} | {_within(logs)} "
              f"| {_rms(logs):.3f} | {_within(t6)} | {held} of {n} |")
    paper = {t.metric: t.value for t in targets}
    out.print(f"\nthe paper: SMC Table 4 / Table 6 {_table4_over_table6(paper, 'smc'):.2f}, "
          f"FLC {_table4_over_table6(paper, 'flc'):.2f}")


def priors(points, base: list, workers: int, out: Page) -> None:
    """The roll / pitch Coulomb friction and the thrust bias, the two values the paper's text bounds,
    at each point of ``points``: the 18 numbers' summary, Table 6's altitude and FLC attitude errors,
    the fit's cost ``0.5 sum(r^2)`` over the 18 log residuals and the same with the paper's priors
    (one residual ``(value - mean) / sigma`` each, as ``rig-gcs identify --paper`` adds them)."""
    from gcs_tools.identify.paper_priors import load_priors

    sigma = {p.key: p for p in load_priors()}
    fr, bias = sigma["joint.coulomb"], sigma["motors.thrust_bias_grf"]
    yaw_coulomb = list(load_config("hilms", overrides=dict(base))["joint.coulomb"])[2]
    out.print("| `joint.coulomb` roll / pitch (N m) | `motors.thrust_bias_grf` (gr.F) | rms log error (within x2 of 18) "
              "| Table 6 ME Z FLC / SMC-FLC (m) | Table 6 FLC ME phi / theta (deg) | cost | cost with the priors |")
    out.print("|---|---|---|---|---|---|---|")
    targets = None
    for c, b in points:
        g, targets = numbers(base + [("joint.coulomb", [c, c, yaw_coulomb]), ("motors.thrust_bias_grf", b)], workers,
                             variant="short")
        logs = _logs(g, targets, [t.metric for t in targets])
        cost = 0.5 * float(np.sum(np.square(logs)))
        prior = 0.5 * (((c - fr.mean) / fr.sigma) ** 2 + ((b - bias.mean) / bias.sigma) ** 2)
        out.print(f"| {c:g} | {b:g} | {_rms(logs):.3f} ({_within(logs)}) "
                  f"| {g['table6.flc.z_m']:.3f} / {g['table6.smc-flc.z_m']:.3f} "
                  f"| {g['table6.flc.phi_deg']:.3f} / {g['table6.flc.theta_deg']:.3f} | {cost:.2f} | {cost + prior:.2f} |")
    paper = {t.metric: t.value for t in targets}
    out.print(f"\nthe paper: Table 6 ME Z FLC / SMC-FLC {paper['table6.flc.z_m']:.3f} / {paper['table6.smc-flc.z_m']:.3f} m, "
              f"FLC ME phi / theta {paper['table6.flc.phi_deg']:.3f} / {paper['table6.flc.theta_deg']:.3f} deg; "
              f"priors {fr.mean:g} +- {fr.sigma:g} N m, {bias.mean:g} +- {bias.sigma:g} gr.F")


def _table4_over_table6(numbers: dict, law: str) -> float:
    """An attitude law's mean roll/pitch error on the harmonic sweep (Table 4) over its error on the
    helix (Table 6; the SMC flies the helix as SMC-FLC's inner loop)."""
    helix = "smc-flc" if law == "smc" else law

    def tilt(prefix):
        return 0.5 * (numbers[f"{prefix}.phi_deg"] + numbers[f"{prefix}.theta_deg"])
    return tilt(f"table4.{law}") / tilt(f"table6.{helix}")


def point(base: list, workers: int, out: Page) -> None:
    mean, targets = numbers(base, workers)
    logs = _logs(mean, targets, [t.metric for t in targets])
    out.print("| number | paper | hilms | ln(hilms / paper) |")
    out.print("|---|---|---|---|")
    for t, lr in zip(targets, logs):
        out.print(f"| {t.metric} | {t.value:.4f} | {mean[t.metric]:.4f} | {lr:+.3f}{' (x2 off)' if abs(lr) > FACTOR_2 else ''} |")
    out.print(f"\nrms log error {_rms(logs):.3f}; {_within(logs)} of {len(logs)} within a "
          f"factor 2")
    level_floor({t.metric: lr for t, lr in zip(targets, logs)}, out)


def level_floor(logs: dict, out: Page) -> float:
    """Print each of :data:`LEVEL_GROUPS`' mean log error and spread about it, and the rms log error
    over all numbers with every group moved to its best common level (its numbers' ratios kept): the
    least a plant that moves only the groups' levels can reach from here. Returns that rms."""
    out.print("\n| group | numbers | mean ln(hilms / paper) | rms about the mean |")
    out.print("|---|---|---|---|")
    spread = []
    for name, patterns in LEVEL_GROUPS.items():
        member = [v for k, v in logs.items() if any(fnmatch.fnmatchcase(k, p) for p in patterns)]
        m = float(np.mean(member))
        dev = [v - m for v in member]
        spread += dev
        out.print(f"| {name} | {len(member)} | {m:+.3f} | {_rms(dev):.3f} |")
    if len(spread) != len(logs):
        raise SystemExit(f"the level groups cover {len(spread)} of the {len(logs)} numbers")
    floor = _rms(spread)
    out.print(f"\nrms log error with every group at its best level: {floor:.3f}")
    return floor


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies paper-numbers", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", choices=("rate-share", "yaw", "delay", "point", "priors"))
    ap.add_argument("--values", help="comma-separated values of the scanned setting (priors: COULOMB:BIAS pairs)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override on every point (repeatable)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--markdown", metavar="FILE",
                    help="also write the tables to FILE, with the command and the machine")
    return ap


def main(argv=None) -> None:
    a = parser().parse_args(argv)
    base = [parse_override(item) for item in a.set]
    over = "".join(f", `{k}` = {v!r}" for k, v in base)
    runs = {"delay": "39", "priors": "17"}.get(a.study, "29")
    short = "`--paper-variant short`, " if a.study == "priors" else ""
    out = Page(a.markdown, f"Every point: `rig-gcs identify --paper`'s job list ({short}{runs} headless runs a seed) on "
                           f"`hilms`{over}, mean over seeds 0-2; errors in degrees and metres, `ln(hilms / paper)` "
                           "the log residual the fit minimises.", workers=a.workers)
    if a.study == "point":
        point(base, a.workers, out)
    elif a.study == "priors":
        pts = ([tuple(float(x) for x in v.split(":")) for v in a.values.split(",")] if a.values
               else list(PRIOR_POINTS))
        priors(pts, base, a.workers, out)
    else:
        study, default = {"rate-share": (rate_share, RATE_SHARES), "yaw": (yaw, YAW_TORQUES),
                          "delay": (delay, DELAYS)}[a.study]
        values = [float(v) for v in a.values.split(",")] if a.values else list(default)
        study(values, base, a.workers, out)
    out.write()

if __name__ == "__main__":
    main()
