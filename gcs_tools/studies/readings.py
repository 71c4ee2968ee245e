"""The readings table of docs/explanation/readings.md: every reading of Eq. 41 and of the motor ceiling
against every claim of the paper, measured.

Each reading is a set of parameter overrides on one plant (default ``hilms-ideal``: the
reading on its own, no hardware effects); every experiment of ``rig-gcs reproduce`` runs
under it (headless; the rectangle's verdicts from its headless twin) and its verdicts are
counted. Prints the markdown table (and writes it with ``--markdown FILE``)::

    python -m gcs_tools.studies readings -o /tmp/readings            # seed 0, all readings
    python -m gcs_tools.studies readings -o /tmp/readings --seeds 3 --plant hilms-ideal

Readings (docs/explanation/readings.md, "Eq. 41's gains and the 850 gr.F ceiling"):

* K: ``si`` rad/s^2 (as printed), ``thrust`` a thrust difference in N (switching torque K l),
  ``torque`` a torque in N m;
* lambda: ``si`` 1/s, ``deg`` applied to angles in degrees against rates in rad/s,
  ``time-constant`` seconds;
* the 850 gr.F ceiling against Eq. 40's 714 gr.F at 15 V: ``eq40`` (as printed: 714 gr.F
  reachable), ``supply`` (a 17.85 V supply: 850 gr.F reachable on Eq. 40, the controllers
  know), ``convex`` (the true curve is convex through hover and reaches 850 gr.F at 15 V, the
  controllers invert Eq. 40).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from gcs_tools.studies.page import Page

#: Eq. 40 at the 850 gr.F ceiling: the supply that reaches it.
SUPPLY_FOR_850_V = 850.0 / 47.62
#: The convex curve through hover (557.7 gr.F at 11.71 V for 2.23 kg) reaching 850 gr.F at 15 V.
HOVER_GRF = 2.23 * 9.81 / 4.0 / 9.80665e-3
CONVEX_EXPONENT = round(math.log(850.0 / HOVER_GRF) / math.log(15.0 / (HOVER_GRF / 47.62)), 3)

CEILINGS = {
    "eq40": {},
    "supply": {"motors.voltage_max": round(SUPPLY_FOR_850_V, 3)},
    "convex": {"motors.curve_exponent": CONVEX_EXPONENT},
}


def reading(k: str, lam: str, ceiling: str = "eq40") -> tuple[str, dict]:
    label = f"K {k}, lambda {lam}, {ceiling}"
    over = {"smc.gain_reading": k, "smc.lambda_reading": lam, **CEILINGS[ceiling]}
    return label, over


#: Each unit of K and of lambda at least once, the combinations that matter, and the three ceilings.
READINGS = (
    reading("si", "si"),
    reading("si", "deg"),
    reading("thrust", "si"),
    reading("thrust", "deg"),
    reading("thrust", "time-constant"),
    reading("torque", "deg"),
    reading("thrust", "deg", "supply"),
    reading("thrust", "deg", "convex"),
)


def _from_results(path: Path, over: dict, n_seeds: int):
    """The sections of an earlier run of the same reading (results.json), or None."""
    import json

    from gcs_tools.reproduce.experiment import Section, Verdict

    if not path.is_file():
        return None
    doc = json.loads(path.read_text())
    plants = doc.get("plants") or {}
    if len(plants) != 1:
        return None
    (col,) = plants.values()
    if col["overrides"] != over or len(col["seeds"]) != n_seeds:
        return None
    secs = [Section(name, e["title"], e["paper"], "", [], e["numbers"],
                    [Verdict(v["claim"], v["status"], v["evidence"]) for v in e["verdicts"]])
            for name, e in doc["experiments"].items()]
    if len(col["seeds"]) != 1:
        return None
    return {col["seeds"][0]: secs}


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m gcs_tools.studies readings", description=__doc__.split("\n\n")[0])
    p.add_argument("-o", "--output", required=True, help="directory for each reading's report")
    p.add_argument("--plant", default="hilms-ideal", help="airframe preset the readings run on: %(default)s")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--seeds", type=int, default=1, help="seeds per reading: %(default)s")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--only-reading", action="append", help="labels' substring filter (repeatable)")
    p.add_argument("--markdown", metavar="FILE",
                   help="also write the table to FILE, with the command and the machine")
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    seeds = (f"seed {args.seed}" if args.seeds == 1 else f"seeds {args.seed}..{args.seed + args.seeds - 1}")
    out = Page(args.markdown, f"Every reading on the plant `{args.plant}`, {seeds}, every experiment of `rig-gcs reproduce` (the "
                              "rectangle's verdicts from its headless run). Columns: K's reading, lambda's reading "
                              "and the ceiling's (`eq40`: as printed, `supply`: a 17.85 V supply, `convex`: the "
                              "convex motor curve).", workers=args.workers)

    from gcs_tools.reproduce.experiments import EXPERIMENTS
    from gcs_tools.reproduce.plants import PlantRuns, plants_markdown
    from gcs_tools.reproduce.runner import reproduce

    names = [e.NAME for e in EXPERIMENTS]
    columns = []
    chosen = [r for r in READINGS if not args.only_reading or any(s in r[0] for s in args.only_reading)]
    for i, (label, over) in enumerate(chosen):
        where = Path(args.output) / label.replace(", ", "_").replace(" ", "-")
        earlier = _from_results(where / "results.json", over, args.seeds)
        if earlier is not None:  # resumed: this reading ran before with the same overrides
            columns.append(PlantRuns(label, args.plant, tuple(sorted(over.items())), earlier))
            continue
        outcome = reproduce(where, seed=args.seed, workers=args.workers, only=names, show_progress=False,
                            plants=(args.plant,), seeds=args.seeds, overrides=over, live=False)
        col = outcome.columns[0]
        columns.append(PlantRuns(label, col.airframe, col.overrides, col.sections))
        print(f"[{i + 1}/{len(chosen)}] {label}: done", file=sys.stderr, flush=True)
    out.print(f"Readings on the plant `{args.plant}`, {seeds} "
              f"(`python -m gcs_tools.studies readings`; the rectangle's verdicts from its headless run):\n", md="")
    out.print(plants_markdown(columns, args.seeds) + "\n")
    out.write()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
