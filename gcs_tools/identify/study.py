"""``rig-gcs identify --calibration-study N``: how far the regression's estimates and 95 % intervals can be
trusted, measured on logs whose truth is known.

Each of the N draws sets every identifiable effect of the ``hilms`` rig at once to a value drawn
uniformly from its plausible range (:data:`DRAW_RANGES`), flies the identification flight (scenario
``sysid``, FLC) with a noise seed of its own (``SEED_BASE + i``; the fit never sees it), writes the
log as a ground station would (.tlog), and identifies it from the ``hilms`` preset, which knows none
of the drawn values. Per parameter: how often the truth lies inside the reported 95 % interval
(coverage) and the median error in per cent of the range. Then the mismatched cases: logs with one
effect the estimator's model lacks or holds at a wrong value (:data:`MISMATCHES`); the model check
must flag them, and flag none of the matched draws.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from gcs_tools.errors import EXIT_OK
from gcs_tools.identify.plausible import PLAUSIBLE_RANGES

SEED_BASE = 1000
DRAW_SEED = 27  # the random draws of the hidden values
#: the hidden values are drawn where a rig of this build plausibly is
DRAW_RANGES = PLAUSIBLE_RANGES
#: name -> (overrides of the log's rig, effects the estimator holds at the preset)
MISMATCHES = {
    "matched (the preset)": ({}, ()),
    "Coulomb friction 2.4x, held": ({"joint.coulomb": [0.12, 0.12, 0.048]}, ("coulomb",)),
    "thrust bias 2x, held": ({"motors.thrust_bias_grf": -100.0}, ("thrust_bias",)),
    "extra mass 100 g at 0.33 m, arm 1": ({"disturbance.extra_masses": [{"arm": 1, "mass": 0.1, "distance": 0.33}]},
                                          ()),
}


def draws(n: int, seed: int = DRAW_SEED) -> list[dict]:
    rng = np.random.default_rng(seed)
    return [{k: float(rng.uniform(lo, hi)) for k, (lo, hi) in DRAW_RANGES.items()} for _ in range(n)]


def as_overrides(values: dict) -> dict:
    """{"joint.viscous[0]": v, ...} -> whole list keys over the hilms preset's."""
    from rig_emulator.config.loader import load_config

    base = load_config(airframe="hilms", scenario="sysid")
    out: dict = {}
    for k, v in values.items():
        if "[" in k:
            name, idx = k[:-1].split("[")
            out.setdefault(name, list(base[name]))[int(idx)] = v
        else:
            out[k] = v
    return out


def fly_and_identify(overrides: dict, seed: int, hold=(), strategy: str = "flc"):
    """Fly the sysid scenario on hilms with ``overrides`` and seed, log it as .tlog, identify it."""
    from gcs_tools.identify.regression import identify_log
    from rig_emulator.config.loader import load_config
    from rig_emulator.link.telemetry.tlog_export import export_tlog
    from rig_emulator.simulation.run import Simulation

    cfg = load_config(airframe="hilms", scenario="sysid",
                      overrides={**overrides, "control.strategy": strategy, "sim.seed": seed})
    result = Simulation(cfg).run()
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "sysid.tlog")
        export_tlog(result, path)
        base = load_config(airframe="hilms", scenario="sysid")
        return identify_log(path, base, hold=hold)


def _draw_job(args):
    seed, values = args
    r = fly_and_identify(as_overrides(values), seed)
    return seed, {e.key: (e.value, e.lo, e.hi) for e in r.estimates}, [f.text() for f in r.findings], r.wall_s


def _mismatch_job(args):
    name, (ov, hold), seed = args
    r = fly_and_identify(ov, seed, hold)
    return name, seed, [f.text() for f in r.findings], r.wall_s


def run_study(n: int, workers: int = 2, mismatch_seeds: int = 2, study_seed: int = 0) -> dict:
    """``study_seed`` 0: the draws and noise seeds the intervals' scales were measured on; any other value
    draws other hidden values and flies other noise seeds (an out-of-sample check of the intervals)."""
    ds = draws(n, DRAW_SEED + study_seed)
    base = SEED_BASE + 10_000 * study_seed
    jobs = [(base + i, d) for i, d in enumerate(ds)]
    mjobs = [(name, MISMATCHES[name], base + 500 + s) for name in MISMATCHES for s in range(mismatch_seeds)]
    with ProcessPoolExecutor(max_workers=workers) as ex:
        res = list(ex.map(_draw_job, jobs))
        mres = list(ex.map(_mismatch_job, mjobs))
    rows = {}
    for key, (lo, hi) in DRAW_RANGES.items():
        inside, errs, zs = 0, [], []
        for k, (_, est, _, _) in enumerate(res):
            v, a, b = est[key]
            truth = ds[k][key]
            inside += a <= truth <= b
            errs.append(abs(v - truth) / (hi - lo))
            if b > a:  # the stated sigma: the 95 % interval's half-width over 1.96
                zs.append((v - truth) / ((b - a) / (2 * 1.96)))
        rows[key] = {"coverage": inside / n, "median_error_pct": 100.0 * float(np.median(errs)),
                     "within_10pct": float(np.mean(np.array(errs) <= 0.1)),
                     "scatter_over_sigma": float(np.sqrt(np.mean(np.square(zs)))) if zs else None}
    flagged = sum(1 for _, _, f, _ in res if f)
    return {"n": n, "study_seed": study_seed, "seeds": [base, base + n - 1], "rows": rows,
            "matched_draws_flagged": flagged,
            "fit_wall_s_median": float(np.median([w for *_, w in res])),
            "mismatch": [{"case": name, "seed": seed, "flagged": bool(f), "findings": f, "wall_s": w}
                         for name, seed, f, w in mres],
            "draws": ds, "estimates": {seed: est for seed, est, _, _ in res},
            "findings": {seed: f for seed, _, f, _ in res}}


def table_lines(study: dict) -> list[str]:
    a, b = study["seeds"]
    lines = [f"calibration study: {study['n']} hidden draws on hilms (sysid flight, FLC), study seed "
             f"{study['study_seed']}, logs from seeds {a}..{b}",
             f"{'parameter':30s} {'range':>18s} {'coverage of 95 %':>17s} {'median error':>13s} {'within 10 %':>12s} "
             f"{'scatter / sigma':>16s}"]
    for key, r in study["rows"].items():
        lo, hi = DRAW_RANGES[key]
        zs = "-" if r["scatter_over_sigma"] is None else f"{r['scatter_over_sigma']:.2f}"
        lines.append(f"{key:30s} {f'{lo:g}..{hi:g}':>18s} {r['coverage']:>16.0%} {r['median_error_pct']:>11.1f} % "
                     f"{r['within_10pct']:>11.0%} {zs:>16s}")
    lines.append(f"matched draws the model check flagged: {study['matched_draws_flagged']} of {study['n']}; "
                 f"median fit wall time {study['fit_wall_s_median']:.1f} s")
    lines.append("model check on the mismatched cases (the estimator's model lacks the effect or holds it):")
    for m in study["mismatch"]:
        what = ("FLAGGED: " + "; ".join(m["findings"][:2]) + (" ..." if len(m["findings"]) > 2 else "")
                if m["flagged"] else "silent")
        lines.append(f"  {m['case']} (seed {m['seed']}): {what}")
    return lines


def _group(keys):
    """Rows of the markdown table: the per-axis / per-motor keys of one effect on one line."""
    out: dict = {}
    for k in keys:
        out.setdefault(k.split("[")[0], []).append(k)
    return out


def markdown_page(study: dict, command: str, machine: str) -> str:
    """The study as the docs' generated page (docs/generated/identify-calibration.md)."""
    a, b = study["seeds"]
    lines = [f"Written by `python scripts/docs_gen.py --identify-study FILE.json` from the `--json` file of `{command}`: "
             f"{study['n']} hidden draws on `hilms` (study seed {study['study_seed']}, flights with noise seeds "
             f"{a}..{b}; the intervals' scales were measured on other draws and seeds), median fit "
             f"{study['fit_wall_s_median']:.1f} s wall{' on ' + machine if machine else ''}.", "",
             "| parameter | range drawn | 95 % interval holds the truth | median error (% of range) | "
             "within 10 % of range | scatter / stated sigma |", "|---|---|---|---|---|---|"]
    for base, keys in _group(study["rows"]).items():
        rows = [study["rows"][k] for k in keys]
        ranges = [f"{DRAW_RANGES[k][0]:g}..{DRAW_RANGES[k][1]:g}" for k in keys]
        drawn = ranges[0] if len(set(ranges)) == 1 else " / ".join(ranges)
        name = base + (" " + " / ".join(k[len(base):] for k in keys) if len(keys) > 1 else "")
        sig = " / ".join("-" if r["scatter_over_sigma"] is None else f"{r['scatter_over_sigma']:.2f}" for r in rows)
        cov = " / ".join(f"{r['coverage']:.0%}" for r in rows)
        err = " / ".join(f"{r['median_error_pct']:.1f}" for r in rows)
        close = " / ".join(f"{r['within_10pct']:.0%}" for r in rows)
        lines.append(f"| {name} | {drawn} | {cov} | {err} | {close} | {sig} |")
    lines += ["", f"Model check: {study['matched_draws_flagged']} of {study['n']} matched draws flagged.", "",
              "| log | seed | model check |", "|---|---|---|"]
    for m in study["mismatch"]:
        what = ("flagged: " + "; ".join(m["findings"][:2]) + (" ..." if len(m["findings"]) > 2 else "")
                if m["flagged"] else "silent")
        lines.append(f"| {m['case']} | {m['seed']} | {what} |")
    flagged = [(seed, f) for seed, f in study.get("findings", {}).items() if f]
    if flagged:
        lines += ["", "Matched draws flagged:", ""]
        lines += [f"* seed {seed}: " + "; ".join(f[:2]) for seed, f in flagged]
    return "\n".join(lines) + "\n"


def cmd_study(args) -> int:
    from protocol.atomic_file import atomic_write_text

    study = run_study(args.calibration_study, workers=args.workers or 2, study_seed=args.study_seed)
    for line in table_lines(study):
        print(line)
    if args.json:
        atomic_write_text(args.json, json.dumps(study, indent=1, default=lambda x: float(x) if math.isfinite(x)
                                                else None) + "\n")
    return EXIT_OK
