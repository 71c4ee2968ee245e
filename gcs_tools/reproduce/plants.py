"""The reproduction on several plants and seeds side by side (section 5).

``rig-gcs reproduce`` runs every experiment on the hardware rig (``hilms``) and the ideal
plant (``hilms-ideal``), each over three seeds; the readings table (python -m gcs_tools.studies readings)
runs them on one plant under several readings of the paper. This module turns the sections
of each (plant, seed) run into

* a verdict per claim and plant over the seeds: **reproduced** when most seeds reproduce it,
  **partly** when most seeds reproduce it at least partly, **not reproduced** otherwise
  (:func:`combine`);
* the paper's published numbers next to each plant's, averaged over the seeds (Table 4,
  Table 6, the rectangle of Fig. 19; :func:`key_numbers`);
* the markdown of both (:func:`plants_markdown`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_tools.reproduce import paper_data
from gcs_tools.reproduce.experiment import NOT_REPRODUCED, PARTLY, REPRODUCED, fmt, status_letter, table
from gcs_tools.reproduce.paper_data import CLAIMS
from protocol.mean_error import COLUMNS

#: The plants ``rig-gcs reproduce`` compares (airframe presets): the hardware rig first.
PLANTS = ("hilms", "hilms-ideal")
#: Seeds per plant.
SEEDS = 3


@dataclass
class PlantRuns:
    """One column of the comparison: a plant (and reading), its sections per seed."""

    label: str
    airframe: str
    overrides: tuple
    sections: dict  # seed -> list of Section


def _statuses(runs: PlantRuns) -> dict:
    out: dict = {}
    for seed in sorted(runs.sections):
        for s in runs.sections[seed]:
            for v in s.verdicts:
                out.setdefault(v.claim, []).append(v.status)
    return out


def combine(statuses: list) -> str:
    """Verdict over seeds: most reproduce it -> reproduced; most at least partly -> partly."""
    n = len(statuses)
    if n == 0:
        return "not run"
    full = sum(s == REPRODUCED for s in statuses)
    part = sum(s in (REPRODUCED, PARTLY) for s in statuses)
    if 2 * full > n:
        return REPRODUCED
    if 2 * part > n:
        return PARTLY
    return NOT_REPRODUCED


def verdicts(runs: PlantRuns) -> dict:
    """claim -> (combined verdict, per-seed statuses)."""
    return {c: (combine(st), st) for c, st in _statuses(runs).items()}


def count(runs: PlantRuns) -> dict:
    v = verdicts(runs)
    return {s: sum(x[0] == s for x in v.values()) for s in (REPRODUCED, PARTLY, NOT_REPRODUCED)}


def _section(sections, name):
    for s in sections:
        if s.name == name:
            return s
    return None


def key_numbers(runs: PlantRuns) -> dict:
    """Table 4 / Table 6 / Fig. 19 numbers averaged over the seeds ({} for experiments not run)."""
    acc: dict = {}
    for seed, sections in runs.sections.items():
        sw = _section(sections, "sweep")
        if sw is not None:
            for strat, d in sw.numbers["table4_average_deg"].items():
                for c, v in d.items():
                    acc.setdefault(("table4", strat, c), []).append(v)
        hx = _section(sections, "helix")
        if hx is not None:
            for strat, d in hx.numbers["mean_errors"].items():
                for c in COLUMNS:
                    acc.setdefault(("table6", strat, c), []).append(d[c])
        rc = _section(sections, "rectangle")
        if rc is not None:
            for c in ("x_m", "y_m"):
                acc.setdefault(("fig19", "smc-flc", c), []).append(rc.numbers["mean_errors_mavlink"][c])
    return {k: float(np.mean(v)) for k, v in acc.items()}


def paper_numbers() -> dict:
    out = {}
    for strat, d in paper_data.TABLE_4.items():
        for c, v in d.items():
            out[("table4", strat, c)] = v
    for strat, d in paper_data.TABLE_6.items():
        for c in COLUMNS:
            out[("table6", strat, c)] = d[c]
    for c, v in paper_data.RECTANGLE_ME.items():
        out[("fig19", "smc-flc", c)] = v
    return out


def within_factor(ours: float, paper: float, factor: float = 2.0) -> bool:
    return ours > 0 and paper > 0 and math.isfinite(ours) and 1.0 / factor <= ours / paper <= factor


_STATUS_SHORT = {REPRODUCED: "yes", PARTLY: "partly", NOT_REPRODUCED: "no"}


def plants_markdown(columns: list, n_seeds: int) -> str:
    """The side-by-side section: claim verdicts and key numbers, paper | each column."""
    heads = [c.label for c in columns]
    lines = [f"Each experiment ran on every plant below with {n_seeds} seed(s); a plant's verdict on a claim is "
             "the majority over its seeds (per-seed verdicts in brackets: y = reproduced, p = partly, n = not).", ""]
    counts = [count(c) for c in columns]
    lines.append(table(["", *heads], [["claims reproduced (partly)",
                                        *[f"{k[REPRODUCED]} ({k[PARTLY]}) of {sum(k.values())}" for k in counts]]]))
    lines.append("")
    ver = [verdicts(c) for c in columns]
    rows = []
    for claim, (text, where) in CLAIMS.items():
        cells = []
        for v in ver:
            if claim not in v:
                cells.append("-")
                continue
            overall, per = v[claim]
            short = "".join(status_letter(s) for s in per)
            cells.append(f"**{_STATUS_SHORT.get(overall, overall)}** [{short}]")
        rows.append([f"{text} ({where})", *cells])
    lines.append(table(["claim of the paper", *heads], rows))
    nums = [key_numbers(c) for c in columns]
    paper = paper_numbers()
    rows = []
    for key, pv in paper.items():
        if not any(key in n for n in nums):
            continue
        what, strat, col = key
        name = {"table4": "Table 4", "table6": "Table 6", "fig19": "Fig. 19"}[what]
        cells = []
        for n in nums:
            v = n.get(key)
            cells.append("-" if v is None else fmt(v, 4) + ("" if within_factor(v, pv) else " (x2 off)"))
        rows.append([f"{name} {strat.upper()} ME {col}", fmt(pv, 4), *cells])
    if rows:
        lines += ["", f"Published numbers next to each plant's (mean over the seeds; \"x2 off\": not within a factor "
                      "of 2 of the paper's):", ""]
        lines.append(table(["", "paper", *heads], rows))
    return "\n".join(lines)


def plants_json(columns: list) -> dict:
    out = {}
    for c in columns:
        v = verdicts(c)
        out[c.label] = {"airframe": c.airframe, "overrides": dict(c.overrides),
                        "seeds": sorted(c.sections),
                        "verdicts": {k: {"combined": x[0], "per_seed": x[1]} for k, x in v.items()},
                        "counts": count(c),
                        "key_numbers": {"/".join(k): x for k, x in key_numbers(c).items()}}
    return out
