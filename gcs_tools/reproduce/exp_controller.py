"""Your controller next to the paper's: ``rig-gcs reproduce -o DIR --controller package.module:Name``.

The comparison as an experiment of the reproduction: for each (plant, seed) it flies every
controller plug-in and the paper's four controllers on the experiments of
:data:`gcs_tools.reproduce.compare.EXPERIMENTS` (:func:`gcs_tools.reproduce.compare.jobs`),
then measures them (:func:`gcs_tools.reproduce.compare.metrics`), draws the figures with every
controller in (:mod:`gcs_tools.reproduce.compare_figures`) and writes the seed's metrics to
``DIR/runs/PLANT-seedN/metrics.json``. The tables over the seeds and the verdicts are
:mod:`gcs_tools.reproduce.compare_report`'s.

A plug-in keeps the loops it does not replace from ``--strategy`` (default ``smc-flc``, the
paper's proposal): on the attitude-only experiments (shocks, harmonic, sweep, masses) a
position-only plug-in flies with that strategy's attitude loop.

A plug-in that raises on a run fails its experiment on that (plant, seed): its metrics there are
failed runs, its error is kept (``raised``) and reported, and the comparison goes on.
"""

from __future__ import annotations

import json
from pathlib import Path

from gcs_tools.reproduce import compare, compare_figures
from gcs_tools.reproduce.experiment import Context, Section, jsonable
from protocol.atomic_file import atomic_write_text
from rig_emulator.sweep import JobFailed

NAME = "controller"
TITLE = "Your controller next to the paper's"
PAPER = "Figs. 12-16, 19, Tables 4 and 6"
METRICS_FILE = "metrics.json"


def jobs(ctx: Context) -> list:
    return compare.jobs(ctx)


def run_dir(ctx: Context) -> Path:
    """``DIR/runs/PLANT-seedN`` of this context (the first (plant, seed) writes its figures to DIR itself)."""
    here = Path(ctx.out_dir)
    name = f"{ctx.airframe}-seed{ctx.seed}"
    root = here.parent.parent if here.parent.name == "runs" and here.name == name else here
    return root / "runs" / name


def _run_entry(r) -> dict:
    head = {"label": r.job.label, "scenario": r.job.scenario, "strategy": r.job.strategy,
            "controller": r.job.controller}
    if isinstance(r, JobFailed):
        return {**head, "raised": r.message}
    return {**head, "sim_time_s": r.sim_time_s, "steps": r.steps, "digest": r.digest()}


def analyse(ctx: Context, results: list, live=None) -> Section:
    numbers = compare.metrics(results)
    figs = compare_figures.draw(ctx, [r for r in results if not isinstance(r, JobFailed)])
    where = run_dir(ctx)
    where.mkdir(parents=True, exist_ok=True)
    doc = {"airframe": ctx.airframe, "seed": ctx.seed, "quick": ctx.quick, "controller": ctx.controller,
           "strategy": ctx.strategy, "overrides": dict(ctx.overrides), "metrics": numbers,
           "runs": [_run_entry(r) for r in results]}
    atomic_write_text(where / METRICS_FILE, json.dumps(jsonable(doc), indent=1, sort_keys=True) + "\n")
    body = (f"Plant `{ctx.airframe}`, seed {ctx.seed}: {len(results)} runs, metrics in "
            f"`runs/{where.name}/{METRICS_FILE}`.")
    return Section(NAME, TITLE, PAPER, body, figs, numbers, [])
