"""``report.md`` and the ``comparison`` part of ``results.json`` of ``rig-gcs reproduce --controller``.

Made of the per-seed metrics of :mod:`gcs_tools.reproduce.exp_controller` (one section per
plant and seed): tables of every metric per controller over the seeds (mean and min-max), the
verdicts of each plug-in against each of the paper's controllers
(:func:`gcs_tools.reproduce.compare.verdict`), and, apart and labelled as such, the fidelity
check of the paper's own controllers against the paper's published numbers (it says how far the
emulator is from the paper's rig; it is not a grade of your controller).
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.reproduce import compare, paper_data
from gcs_tools.reproduce.experiment import fmt, table
from gcs_tools.reproduce.plants import within_factor
from protocol.mean_error import COLUMNS

SHORT = {compare.BETTER: "better", compare.WORSE: "worse", compare.SAME: "same"}


def _per_seed(column) -> dict:
    """seed -> the controller section's metrics {exp: {controller: {metric: value}}}."""
    out = {}
    for seed in sorted(column.sections):
        for s in column.sections[seed]:
            if s.name == "controller":
                out[seed] = s.numbers
    return out


def values(column, exp: str, who: str, key: str) -> list:
    """One metric of one controller on one plant, per seed (seed order)."""
    return [m[exp][who][key] for m in _per_seed(column).values() if exp in m and who in m[exp]]


def cell(vals: list, digits: int) -> str:
    """mean (min-max) over the seeds; failed runs (inf) counted apart."""
    v = [float(x) for x in vals]
    fin = [x for x in v if math.isfinite(x)]
    n, k = len(v), len(v) - len(fin)
    if n == 0:
        return "-"
    if not fin:
        return "failed" + (f" ({k}/{n})" if n > 1 else "")
    s = fmt(np.mean(fin), digits)
    if len(fin) > 1:
        s += f" ({fmt(min(fin), digits)}-{fmt(max(fin), digits)})"
    if k:
        s += f"; failed in {k}/{n}"
    return s


def _exps(columns) -> list:
    seen = []
    for c in columns:
        for m in _per_seed(c).values():
            seen += [e for e in m if e not in seen]
    return [e for e in compare.EXPERIMENTS if e in seen]


def raised(columns) -> list[tuple[str, str, int, str]]:
    """(plant, plug-in, seed, "experiment[/variant]: error") of every plug-in run that raised."""
    out = []
    for c in columns:
        for seed, m in _per_seed(c).items():
            for exp in compare.EXPERIMENTS:
                for who, x in m.get(exp, {}).items():
                    out += [(c.label, who, seed, text) for text in x.get("raised", ())]
    return out


def verdicts(column, spec: str) -> dict:
    """{plug-in: {paper controller: {(exp, metric key): verdict}}} on one plant."""
    out = {}
    for p in compare.plugins(spec):
        out[p] = {}
        for q in compare.PAPER_CONTROLLERS:
            out[p][q] = {}
            for exp in _exps([column]):
                for m in compare.METRICS[exp]:
                    mine, theirs = values(column, exp, p, m.key), values(column, exp, q, m.key)
                    if mine and theirs:
                        out[p][q][(exp, m.key)] = compare.verdict(mine, theirs, m.atol, m.higher_is_better)
    return out


def counts(v: dict) -> dict:
    """{verdict: how many} of one plug-in against one paper controller."""
    return {s: sum(x == s for x in v.values()) for s in (compare.BETTER, compare.SAME, compare.WORSE)}


def summary_lines(columns, spec: str) -> list[str]:
    """One line per plant, plug-in and paper controller (what the command prints)."""
    out = []
    for c in columns:
        for p, by in verdicts(c, spec).items():
            for q, v in by.items():
                k = counts(v)
                out.append(f"{compare.label(p, spec)} (yours) on {c.label} vs {q.upper()}: better on {k['better']}, "
                           f"same on {k['same']}, worse on {k['worse']} of {len(v)} metrics")
    return out


def _relative(mine: list, theirs: list, metric) -> str:
    """How the means compare, for a verdict cell: yours as a multiple of theirs ("0.27x"), counts as
    "4 vs 2"; "" where a failed run leaves no mean."""
    a, b = float(np.mean(mine)), float(np.mean(theirs))
    if not (math.isfinite(a) and math.isfinite(b)):
        return ""
    if metric.higher_is_better:
        return f"{a:g} vs {b:g}"
    if not b > 0:
        return ""
    r = a / b
    return f"{r:.2f}x" if r >= 0.01 else f"{r:.1g}x"


def fidelity_rows(column) -> list:
    """The paper's published numbers the compared runs also measure, for the paper's own controllers:
    [what, paper's value, ours (mean over the seeds), within a factor 2]."""
    rows = []
    exps = _exps([column])
    if "sweep" in exps:
        for q in ("smc", "flc"):
            for k in ("phi_deg", "theta_deg"):
                rows.append((f"Table 4 {q.upper()} ME {k}", paper_data.TABLE_4[q][k], values(column, "sweep", q, k)))
    if "helix" in exps:
        for q in ("flc", "smc-flc"):
            for k in COLUMNS:
                rows.append((f"Table 6 {q.upper()} ME {k}", paper_data.TABLE_6[q][k], values(column, "helix", q, k)))
    if "rectangle" in exps:
        for k in ("x_m", "y_m"):
            rows.append((f"Fig. 19 SMC-FLC ME {k} (headless)", paper_data.RECTANGLE_ME[k],
                         values(column, "rectangle", "smc-flc", k)))
    out = []
    for what, paper, ours in rows:
        mean = float(np.mean(ours)) if ours else math.nan
        out.append([what, paper, mean, within_factor(mean, paper)])
    return out


def render(sections, seed: int, quick: bool, columns, n_seeds: int, spec: str, strategy: str, opts: str,
           version: str) -> str:
    """The comparison report; ``sections``: the first plant's first seed (its figures are in DIR)."""
    from rig_emulator.controllers import load_controller

    plugins = compare.plugins(spec)
    plants = [c.label for c in columns]
    exps = _exps(columns)
    lines = ["# Your controller next to the paper's", ""]
    lines.append(f"Generated by `rig-gcs reproduce {opts}` (hilms-sil {version}). Every controller below flew the "
                 f"same scenarios with the same seeds ({', '.join(str(s) for s in range(seed, seed + n_seeds))}) on "
                 f"the plant(s) {', '.join(f'`{p}`' for p in plants)}: the paper's four controllers (the built-in "
                 "strategies SMC, FLC, SMC-FLC and PID, with the presets' gains) and yours.")
    lines.append("")
    rows = []
    for p in plugins:
        replaces = load_controller(p).replaces
        kept = {"both": "none", "attitude": f"position loop of `{strategy}`",
                "position": f"attitude loop of `{strategy}`"}.get(replaces, replaces)
        rows.append([f"**{compare.label(p, spec)}** (yours)", f"`{p}`", replaces, kept])
    for q in compare.PAPER_CONTROLLERS:
        rows.append([q.upper(), f"built-in strategy `{q}`", "both", "none"])
    lines += [table(["controller", "what", "loops it flies", "loops kept from a built-in"], rows), ""]
    from gcs_tools.reproduce.settings_line import settings_line as _settings_line

    lines += [_settings_line(plants[0]).replace("the detailed sections below show", "the figures below show"), ""]
    if any(load_controller(p).replaces == "position" for p in plugins):
        lines += ["A position-only controller does not fly the attitude-only experiments (shocks, harmonic, sweep, "
                  f"masses): there its rows are the attitude loop of `{strategy}` it keeps.", ""]
    lines += ["SMC-FLC is the paper's SMC attitude loop under its FLC position loop: on the experiments without a "
              "position loop (shocks, harmonic, sweep, masses) it flies as SMC, and its rows there are SMC's.", ""]
    if quick:
        lines += ["**Quick mode**: shortened runs and fewer frequencies and masses, to check that the pipeline works; "
                  "its numbers and verdicts are not the comparison's.", ""]
    lines += ["## How to read the verdicts", "",
              "Each metric is measured per seed; the tables give the mean over the seeds and, in brackets, the "
              "smallest and largest seed (the seed spread). Lower is better except where the metric says otherwise "
              "(masses held, waypoints reached). A verdict compares your controller with one of the paper's on one "
              "metric and plant: " + compare.RULE + " In brackets: your mean as a multiple of theirs (the counts "
              "side by side).", ""]
    errors = raised(columns)
    if errors:
        lines += ["## Runs that raised", "",
                  "These runs stopped with an error of the controller. Each counts as a failed run of its "
                  "experiment, on that plant and seed, in the tables and verdicts below; the other experiments "
                  "were flown and compared as usual.", ""]
        lines += [f"- **{compare.label(who, spec)} (yours)** on `{plant}`, seed {s}, {text}"
                  for plant, who, s, text in errors]
        lines.append("")
    lines += ["## Verdicts", ""]
    for c in columns:
        v = verdicts(c, spec)
        for p in plugins:
            heads = [f"vs {q.upper()}" for q in compare.PAPER_CONTROLLERS]
            k = {q: counts(v[p][q]) for q in compare.PAPER_CONTROLLERS}
            lines += [f"**{compare.label(p, spec)} (yours)** on `{c.label}` ({len(_per_seed(c))} seed(s)):", ""]
            trows = [["better / same / worse", *[f"{k[q]['better']} / {k[q]['same']} / {k[q]['worse']}"
                                                 for q in compare.PAPER_CONTROLLERS]]]
            for exp in exps:
                for m in compare.METRICS[exp]:
                    cells = []
                    for q in compare.PAPER_CONTROLLERS:
                        x = v[p][q].get((exp, m.key))
                        if x is None:
                            cells.append("-")
                            continue
                        word = f"**{x}**" if x != compare.SAME else x
                        size = _relative(values(c, exp, p, m.key), values(c, exp, q, m.key), m)
                        cells.append(f"{word} ({size})" if size else word)
                    trows.append([f"{compare.TITLES[exp][1]}: {m.label}", *cells])
            lines += [table(["metric", *heads], trows), ""]
    first = {s.name: s for s in sections}.get("controller")
    for i, exp in enumerate(exps, start=1):
        title, where = compare.TITLES[exp]
        lines += [f"## {i}. {title} ({where})", ""]
        fig = next((f for f in (first.figures if first else []) if f == _fig_name(exp)), None)
        if fig:
            lines += [f"![{where}, every controller]({fig})", "",
                      f"(Plant `{plants[0]}`, seed {seed}; the other plants and seeds: `runs/PLANT-seedN/{fig}`.)", ""]
        lines.append(_what(exp, quick))
        for c in columns:
            heads = ["controller", *[m.label for m in compare.METRICS[exp]]]
            trows = []
            for who in compare.PAPER_CONTROLLERS + tuple(plugins):
                name = compare.label(who, spec) + (" (yours)" if who in plugins else "")
                trows.append([f"**{name}**" if who in plugins else name,
                              *[cell(values(c, exp, who, m.key), m.digits) for m in compare.METRICS[exp]]])
            lines += ["", f"`{c.label}`, {len(_per_seed(c))} seed(s):", "", table(heads, trows)]
        lines.append("")
    lines += ["## Fidelity check of the paper's own controllers", "",
              "How far the emulated rig is from the paper's: the paper's published numbers next to the same "
              "controllers' runs above (mean over the seeds), within a factor 2 or not. This is about the emulator, "
              "not about your controller: the paper publishes no number for it.", ""]
    frows = []
    for c in columns:
        for what, paper, ours, ok in fidelity_rows(c):
            frows.append([what, f"`{c.label}`", fmt(paper, 4), fmt(ours, 4), "yes" if ok else "no"])
    if frows:
        lines += [table(["published number", "plant", "paper", "emulated (mean)", "within a factor 2"], frows), ""]
        if quick:
            lines += ["(Quick mode: shortened runs and fewer frequencies, so these are not the paper's conditions.)",
                      ""]
    else:
        lines += ["None of the experiments run has a published number (run sweep, helix or rectangle).", ""]
    lines += ["## Regenerating this report", "",
              f"`rig-gcs reproduce -o DIR {opts}` writes the same `report.md`, `results.json`, figures and "
              "`runs/PLANT-seedN/` (each seed's figures and `metrics.json`) byte for byte on the same installation "
              "(add `--workers N` or `--scheduler tcp://HOST:PORT` to spread the runs). How to read it: "
              "docs/how-to/compare-controllers.md.", ""]
    return "\n".join(lines)


def _fig_name(exp: str) -> str:
    from gcs_tools.reproduce.compare_figures import FILES

    return FILES[exp]


def _what(exp: str, quick: bool) -> str:
    from gcs_tools.reproduce import exp_sweep

    return {
        "shocks": "Scenario `hover-shocks` (attitude references zero, 1 N m shocks for 50 ms on the arms), 500 Hz "
                  "log: per shock the peak deviation, the overshoot past zero and the settling about the final value "
                  "(median over the shocks; failed: none settled), and the chattering (roll and pitch error RMS above "
                  "5 Hz), as in the reproduction's Fig. 12 section.",
        "harmonic": f"phi_des = theta_des = {paper_data.HARMONIC_AMPLITUDE_DEG:g} sin({paper_data.HARMONIC_OMEGA:g} t) "
                    "deg, psi_des = 0: mean errors (Eq. 45) over the run.",
        "sweep": "The harmonic reference at omega = "
                 + ", ".join(f"{w:g}" for w in (exp_sweep.QUICK_OMEGAS if quick else exp_sweep.OMEGAS))
                 + " rad/s: roll and pitch mean errors averaged over the frequencies (Table 4's figure).",
        "masses": "Two equal masses at 0.33 m on arms 1 and 2 ("
                  + ", ".join(f"{m * 1000:g} g" for m in (paper_data.EXTRA_MASSES_KG[-1:] if quick
                                                          else paper_data.EXTRA_MASSES_KG))
                  + "), attitude hold: how many masses each controller held (true roll and pitch within 45 deg), and "
                    "with the heaviest the mean errors and chattering (failed: it diverged).",
        "helix": "Eq. 46 (a 3D line, then a helix rising to 8 m): the six mean errors of Table 6 (Eq. 45) and the "
                 "motor thrusts' RMS above 5 Hz (Fig. 18's \"thinner\" lines).",
        "rectangle": "The 5 m x 3 m waypoint rectangle at 2 m with 8 cm switching, headless (the reproduction flies "
                     "SMC-FLC over MAVLink too): waypoints reached, when the last was reached (failed: not all "
                     "reached), and the X and Y mean errors against the virtual line until then.",
    }[exp]


def results_part(columns, spec: str) -> dict:
    """``results.json``'s ``comparison``: every metric per plant, experiment and controller over the seeds
    (per-seed values and their spread), the verdicts, and the summary the command prints."""
    out = {"rule": compare.RULE, "plugins": compare.plugins(spec), "paper_controllers": list(compare.PAPER_CONTROLLERS),
           "summary": summary_lines(columns, spec),
           "plants": {}, "raised": [{"plant": p, "controller": who, "seed": s, "run": text}
                                    for p, who, s, text in raised(columns)]}
    for c in columns:
        seeds = sorted(_per_seed(c))
        tabs = {}
        for exp in _exps([c]):
            for who in compare.controllers(spec):
                for m in compare.METRICS[exp]:
                    vals = values(c, exp, who, m.key)
                    tabs.setdefault(exp, {}).setdefault(who, {})[m.key] = {"per_seed": vals, **compare.spread(vals)}
        ver = {p: {q: {f"{e}/{k}": x for (e, k), x in v.items()} for q, v in by.items()}
               for p, by in verdicts(c, spec).items()}
        out["plants"][c.label] = {"seeds": seeds, "metrics": tabs, "verdicts": ver,
                                  "fidelity": [{"number": r[0], "paper": r[1], "ours": r[2], "within_factor_2": r[3]}
                                               for r in fidelity_rows(c)]}
    return out
