"""Where the FLC's chattering on ``hilms`` comes from (Fig. 12's "FLC eliminates the chattering SMC
shows in hover with shocks"; docs/explanation/readings.md, "The chattering claims").

    python -m gcs_tools.studies chattering [--seeds 3] [--workers 2]
    python -m gcs_tools.studies chattering --delay-scan [--seeds 3] [--workers 2]
    python -m gcs_tools.studies chattering --markdown FILE     # also write the tables as a docs page

Runs the reproduction's ``hover-shocks`` job (SMC and FLC, 20 s, 500 Hz log) on four kinds of plant:
``hilms-ideal``; ``hilms-ideal`` plus one effect (or reading) of ``hilms``; ``hilms`` minus one (that
key set back to its ``hilms-ideal`` value); ``hilms-ideal`` with the effects of :data:`CUMULATIVE`
added one after another. The effects are the keys on which the two airframes differ
(``load_config``), the SMC's two Eq. 41 readings taken together, and the heading reading together
with the motors' field it reads. Per plant: both controllers' chattering as ``rig-gcs reproduce``
measures it (``exp_shocks.summarise``: RMS above 5 Hz of the roll and pitch errors, what Fig. 12
plots, and of the four motor voltage commands), mean over the seeds, the FLC / SMC ratios and the
claim's verdict per seed (``exp_shocks``' own: y, p, n). Last, for ``hilms``, where the FLC's torque
commands above 5 Hz sit in frequency (share of their power per band, per axis).

``--delay-scan``: both controllers' chattering on ``hilms-ideal`` with the SMC readings of ``hilms``,
per sensing-to-actuation delay in :data:`DELAYS_S`, with Eq. 40's line and with ``hilms``'s convex
motor curve.
"""

from __future__ import annotations

import argparse

import numpy as np

from gcs_tools.reproduce import exp_shocks
from gcs_tools.reproduce.experiment import status_letter
from gcs_tools.studies.page import Page
from rig_emulator.config.loader import load_config
from rig_emulator.sweep import SimJob, run_jobs

STRATEGIES = ("smc", "flc")
GROUPS = {  # keys that act as one reading
    "smc.gain_reading": "SMC readings (Eq. 41)", "smc.lambda_reading": "SMC readings (Eq. 41)",
    "estimation.tau_yaw": "heading read at each sample + motors' field",
    "motor_field.ripple_uT": "heading read at each sample + motors' field",
}
DELAYS_S = (0.0, 0.004, 0.006, 0.008, 0.010, 0.013)
BANDS_HZ = ((5.0, 10.0), (10.0, 20.0), (20.0, 50.0), (50.0, 250.0))
# hilms built up from hilms-ideal in this order (the rest of hilms after the last): the effects whose
# combination makes the FLC's attitude loop ring (measured: none of them alone does)
CUMULATIVE = ("SMC readings (Eq. 41)", "motors.curve_exponent", "control.actuation_delay", "joint.cog_offset",
              "joint.coulomb")


def effects() -> dict[str, dict]:
    """Effect name -> (its ``hilms`` values, its ``hilms-ideal`` values), for every key the two differ on."""
    hw, ideal = load_config("hilms"), load_config("hilms-ideal")
    out: dict[str, dict] = {}
    for key in hw:
        if key == "airframe.name" or hw[key] == ideal[key]:
            continue
        name = GROUPS.get(key, key)
        entry = out.setdefault(name, {"hilms": {}, "ideal": {}})
        entry["hilms"][key], entry["ideal"][key] = hw[key], ideal[key]
    return out


def plants() -> list[tuple[str, str, dict]]:
    """(label, airframe, overrides) of every plant the study runs."""
    fx = effects()
    out = [("hilms-ideal", "hilms-ideal", {}), ("hilms", "hilms", {})]
    for name, values in fx.items():
        out.append((f"hilms-ideal + {name}", "hilms-ideal", values["hilms"]))
    for name, values in fx.items():
        out.append((f"hilms - {name}", "hilms", values["ideal"]))
    built: dict = {}
    for name in CUMULATIVE:
        built.update(fx[name]["hilms"])
        out.append((f"hilms-ideal + ... + {name}", "hilms-ideal", dict(built)))
    return out


def delay_plants() -> list[tuple[str, str, dict]]:
    """(label, airframe, overrides) of the delay scan."""
    fx = effects()
    readings, curve = fx["SMC readings (Eq. 41)"], fx["motors.curve_exponent"]
    out = []
    for name, values in (("Eq. 40's line", curve["ideal"]), ("convex curve", curve["hilms"])):
        for delay in DELAYS_S:
            out.append((f"{name}, delay {delay * 1e3:g} ms", "hilms-ideal",
                        dict(readings["hilms"], **values, **{"control.actuation_delay": delay})))
    return out


def _job(airframe: str, overrides: dict, strategy: str, seed: int, columns: tuple) -> SimJob:
    ov = dict(overrides, **{"sim.log_rate_hz": exp_shocks.LOG_HZ})
    return SimJob("hover-shocks", strategy, seed=seed, overrides=tuple(sorted(ov.items())), airframe=airframe,
                  columns=columns)


def band_shares(t: np.ndarray, x: np.ndarray) -> list[float]:
    """Share of the power of ``x`` above the first band's lower edge that falls in each of :data:`BANDS_HZ`."""
    x = x - x.mean()
    f = np.fft.rfftfreq(x.size, t[1] - t[0])
    p = np.abs(np.fft.rfft(x)) ** 2
    total = p[f >= BANDS_HZ[0][0]].sum()
    return [float(p[(f >= lo) & (f < hi)].sum() / total) for lo, hi in BANDS_HZ]


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies chattering", description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="seeds 0 .. N-1 (default 3)")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--delay-scan", action="store_true", help="the delay scan with and without the convex curve")
    ap.add_argument("--markdown", metavar="FILE",
                    help="also write the tables (as markdown) to FILE, with the command and the machine")
    return ap


def main(argv=None) -> None:
    args = parser().parse_args(argv)
    out = Page(args.markdown, "The reproduction's `hover-shocks` job (Fig. 12), SMC and FLC, 20 s, 500 Hz log, "
                              f"seeds 0-{args.seeds - 1}: chattering as `rig-gcs reproduce` measures it, RMS above "
                              f"{exp_shocks.CUTOFF_HZ:g} Hz of the roll and pitch errors (deg; what Fig. 12 plots "
                              "and the verdict reads) and of the four motor voltage commands (V), mean over the "
                              "seeds; verdicts of the claim \"FLC eliminates the chattering\" per seed (y, p, n).",
               workers=args.workers)
    seeds = range(args.seeds)
    columns = ("t", "euler", "euler_des", "v_cmd")
    runs = delay_plants() if args.delay_scan else plants()
    jobs = [_job(air, ov, s, seed, columns) for _, air, ov in runs for seed in seeds for s in STRATEGIES]
    spectra = [] if args.delay_scan else [_job("hilms", {}, "flc", seed, ("t", "u")) for seed in seeds]
    results = run_jobs(jobs + spectra, workers=args.workers)
    figures = iter(exp_shocks.summarise(r) for r in results[:len(jobs)])

    out.print(f"chattering in hover-shocks, mean over seeds 0-{args.seeds - 1}: RMS above "
              f"{exp_shocks.CUTOFF_HZ:g} Hz of the roll and pitch errors (deg; what Fig. 12 plots and the verdict reads) and of the motor voltage "
              "commands (V)", md="")
    out.print(f"{'plant':58s} {'SMC deg':>8s} {'FLC deg':>8s} {'FLC/SMC':>8s}  verdicts  {'SMC V':>7s} {'FLC V':>7s} "
              f"{'FLC/SMC':>8s}", md="| plant | SMC (deg) | FLC (deg) | FLC / SMC | verdicts | SMC (V) | FLC (V) "
                                     "| FLC / SMC |\n|---|---|---|---|---|---|---|---|")
    for label, _, _ in runs:
        per_seed = [(next(figures), next(figures)) for _ in seeds]
        smc_deg, flc_deg, smc_v, flc_v = np.mean(
            [[a["chattering_deg_rms"], b["chattering_deg_rms"], a["chattering_v_rms"], b["chattering_v_rms"]]
             for a, b in per_seed], axis=0).tolist()
        verdicts = "".join(status_letter(exp_shocks.chattering_verdict(a, b).status) for a, b in per_seed)
        out.print(f"{label:58s} {smc_deg:8.4f} {flc_deg:8.4f} {flc_deg / smc_deg:8.2f}  [{verdicts}]    {smc_v:7.3f} "
                  f"{flc_v:7.3f} {flc_v / smc_v:8.2f}",
                  md=f"| {label} | {smc_deg:.4f} | {flc_deg:.4f} | {flc_deg / smc_deg:.2f} | {verdicts} | {smc_v:.3f} "
                     f"| {flc_v:.3f} | {flc_v / smc_v:.2f} |")
    if spectra:
        head = (f"hilms, FLC: share of the torque commands' power above {BANDS_HZ[0][0]:g} Hz per band, "
                "mean over the seeds")
        out.print("\n" + head, md=f"\nOn `hilms`, the FLC's torque commands: share of their power above "
                                  f"{BANDS_HZ[0][0]:g} Hz per band, mean over the seeds:\n")
        out.print(f"{'axis':6s} " + " ".join(f"{lo:g}-{hi:g} Hz".rjust(11) for lo, hi in BANDS_HZ),
                  md="| axis | " + " | ".join(f"{lo:g}-{hi:g} Hz" for lo, hi in BANDS_HZ) + " |\n|---|"
                     + "---|" * len(BANDS_HZ))
        for k, axis in ((1, "roll"), (2, "pitch"), (3, "yaw")):
            shares = np.mean([band_shares(r.series["t"], r.series["u"][:, k]) for r in results[len(jobs):]], axis=0)
            out.print(f"{axis:6s} " + " ".join(f"{s:11.2f}" for s in shares),
                      md=f"| {axis} | " + " | ".join(f"{s:.2f}" for s in shares) + " |")
    out.write()


if __name__ == "__main__":
    main()
