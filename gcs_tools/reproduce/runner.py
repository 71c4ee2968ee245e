"""Run the reproduction: every experiment's headless jobs in one sweep, the MAVLink flight
beside it, the stability analysis, then figures and the report.

:func:`reproduce` is what ``rig-gcs reproduce`` calls. The headless jobs of all selected
experiments go to :func:`rig_emulator.sweep.run_jobs` together (local processes, or a Dask
cluster with ``scheduler``), so the machine stays busy across experiments. The rectangle's
rig process (always local: it needs loopback sockets) starts once the first headless job
has finished, i.e. once the numba cache is known to be warm, so a cold start compiles the
step loop in the sweep's workers and not a third time in the rig.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

from gcs_tools.errors import OperationError, UsageError
from gcs_tools.reproduce import report
from gcs_tools.reproduce.experiment import Context, Section
from gcs_tools.reproduce.experiments import EXPERIMENTS, NAMES, STABILITY
from gcs_tools.reproduce.plants import PLANTS, SEEDS, PlantRuns
from gcs_tools.reproduce.progress import Progress
from gcs_tools.reproduce.stability_section import stability_section


@dataclass
class Outcome:
    files: list  # paths written (report.md, results.json, figures)
    sections: list  # Section per experiment, report order (the first plant's first seed)
    jobs: int  # headless runs
    sim_seconds: float  # simulated seconds of the headless runs
    columns: list = None  # PlantRuns per plant (every seed's sections)


def select(only) -> tuple[list, bool]:
    """(experiment modules, include the stability section) for ``--only`` names (None: all)."""
    if not only:
        return list(EXPERIMENTS), True
    unknown = [n for n in only if n not in NAMES]
    if unknown:
        raise UsageError(f"--only {', '.join(unknown)}: unknown; choose from {', '.join(NAMES)}")
    return [e for e in EXPERIMENTS if e.NAME in only], STABILITY in only


def prepare_out_dir(path) -> Path:
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"-o {out}: cannot create the directory ({exc})") from None
    return out


class _Live(threading.Thread):
    """An experiment's ``live(ctx)`` in a thread; ``result`` or ``error`` afterwards."""

    def __init__(self, exp, ctx: Context, progress: Progress):
        super().__init__(daemon=True, name=f"reproduce-{exp.NAME}")
        self.exp, self.ctx, self.progress = exp, ctx, progress
        self.result = None
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            self.result = self.exp.live(self.ctx)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            self.error = exc
        self.progress.update(f"{self.exp.NAME} (MAVLink)")


def _plugin_hint(exc, compared: tuple) -> str:
    """What to do when a compared plug-in stops a run: the experiment it failed on, and how to leave it out."""
    job = getattr(exc, "job", None)
    if job is None or not job.controller or not job.label.startswith("controller/"):
        return ""
    from gcs_tools.reproduce.compare import EXPERIMENTS

    exp = job.label.split("/")[1]
    rest = [e for e in (compared or EXPERIMENTS) if e != exp]
    return f"\n{job.controller} failed on the experiment {exp!r}; fix it there" + (
        f", or compare on the others: --only {','.join(rest)}" if rest else "")


def reproduce(out_dir, *, seed: int = 0, workers: int | None = None, scheduler=None, only=None, quick: bool = False,
              show_progress: bool = True, stream=None, plants=PLANTS, seeds: int = SEEDS,
              overrides=None, live: bool = True, controller: str | None = None,
              strategy: str = "smc-flc") -> Outcome:
    """Run the selected experiments and write ``report.md``, ``results.json`` and the figures into ``out_dir``.

    Every experiment runs on each plant of ``plants`` (airframe presets; default the hardware
    rig ``hilms`` and the ideal plant ``hilms-ideal``) with the seeds ``seed .. seed + seeds - 1``,
    ``overrides`` (dotted key -> value) on top of every run. The report's detailed sections,
    figures and the MAVLink flight are the first plant's first seed; the other runs' figures go
    to ``DIR/runs/PLANT-seedN/`` and their rectangle is the headless twin (``live=False``: the
    first one's too, no rig process).

    ``controller`` (``package.module:Name``, several comma-separated or as a list): compare those
    controller plug-ins with the paper's four controllers instead of reproducing the paper's claims
    (:mod:`gcs_tools.reproduce.exp_controller`, :mod:`gcs_tools.reproduce.compare`), keeping the
    loops of ``strategy`` they do not replace, on the experiments ``only`` names among
    :data:`gcs_tools.reproduce.compare.EXPERIMENTS` (all of them without ``only``); every
    (plant, seed) also gets ``DIR/runs/PLANT-seedN/metrics.json``.
    """
    from rig_emulator.config.loader import ConfigError
    from rig_emulator.sweep import JobFailed, run_jobs

    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise UsageError(f"--seed {seed!r}: must be an integer >= 0")
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise UsageError(f"--seeds {seeds!r}: must be an integer >= 1")
    plants = tuple(plants)
    if not plants:
        raise UsageError("--plant: name at least one airframe preset")
    from rig_emulator.config.loader import available

    unknown = [p for p in plants if p not in available("airframes")]
    if unknown:
        raise UsageError(f"--plant {', '.join(unknown)}: unknown; choose from {', '.join(available('airframes'))}")
    from rig_emulator.config.loader import check_config

    for plant in plants:  # bad overrides are refused before anything runs
        try:
            check_config(plant, None, overrides or None)
        except ConfigError as exc:
            raise UsageError(f"--set: {exc}") from None
    compared = ()
    if controller:
        from gcs_tools.reproduce import compare, exp_controller
        from rig_emulator.controllers import PluginError, load_controller

        names = list(controller) if isinstance(controller, (list, tuple)) else [controller]
        names = [p for n in names for p in compare.plugins(n)]
        if len(set(names)) != len(names):
            raise UsageError(f"--controller: {', '.join(sorted({n for n in names if names.count(n) > 1}))} "
                             "given twice")
        for name in names:
            try:
                from rig_emulator.config.loader import fold_plugin_params

                # a plug-in that cannot load, or a --set controller.params.NAME it refuses, is a usage
                # error, before anything runs
                load_controller(name, fold_plugin_params(overrides or {}).get("controller.params"))
            except PluginError as exc:
                raise UsageError(f"--controller: {exc}") from None
        controller = ",".join(names)
        if only:
            bad = [n for n in only if n not in compare.EXPERIMENTS]
            if bad:
                raise UsageError(f"--only {', '.join(bad)}: not compared with --controller; choose from "
                                 f"{', '.join(compare.EXPERIMENTS)}")
            compared = tuple(e for e in compare.EXPERIMENTS if e in only)
        exps, with_stability = [exp_controller], False
    else:
        exps, with_stability = select(only)
    out = prepare_out_dir(out_dir)
    pairs = tuple(sorted((overrides or {}).items()))
    contexts = []
    for plant in plants:
        for s in range(seed, seed + seeds):
            primary = not contexts
            where = out if primary else out / "runs" / f"{plant}-seed{s}"
            contexts.append(Context(seed=s, quick=quick, out_dir=where, airframe=plant, overrides=pairs,
                                    controller=controller or "", strategy=strategy, compare=compared))
    main = contexts[0]
    jobs, spans = [], {}
    for i, ctx in enumerate(contexts):  # contexts are keyed by position (their overrides may hold lists)
        for exp in exps:
            mine = exp.jobs(ctx)
            spans[(i, exp.NAME)] = (len(jobs), len(jobs) + len(mine))
            jobs += mine
    lives = [e for e in exps if hasattr(e, "live")] if live else []
    progress = Progress(len(jobs) + len(lives) + int(with_stability), stream=stream, enabled=show_progress)
    threads = [_Live(e, main, progress) for e in lives]
    started = threading.Event()

    def start_live():
        if not started.is_set():
            started.set()
            for t in threads:
                t.start()

    def on_job(done, total, job):
        progress.update(job.label or job.describe())
        start_live()

    try:
        if not jobs:
            start_live()
        try:
            # a plug-in's run that raises is a failed run of the comparison, not the end of it
            results = run_jobs(jobs, workers=workers, scheduler=scheduler, progress=on_job, keep_failed=bool(controller))
        except (JobFailed, ConfigError) as exc:
            raise OperationError(str(exc) + _plugin_hint(exc, compared)) from None
        except OSError as exc:  # e.g. a Dask scheduler that cannot be reached
            raise OperationError(f"running the simulations failed: {exc}") from None
        start_live()
        stab_md, stab = (None, None)
        if with_stability:
            stab_md, stab = stability_section()
            progress.update(STABILITY)
    finally:
        for t in threads:
            if t.is_alive():
                t.join()
        progress.close()
    for t in threads:
        if t.error is not None:
            if isinstance(t.error, (OperationError, UsageError)):
                raise t.error
            raise OperationError(f"{t.exp.NAME}: {type(t.error).__name__}: {t.error}") from t.error
    failed = [r for r in results if isinstance(r, JobFailed)]  # plug-in runs that raised (--controller)
    for f in failed:
        if not f.job.controller:  # a paper controller's run: the emulator's fault, not the comparison's
            raise OperationError(str(f))
    flown = {t.exp.NAME: t.result for t in threads}
    by_ctx = []
    for i, ctx in enumerate(contexts):
        if ctx is not main:
            ctx.out_dir.mkdir(parents=True, exist_ok=True)
        secs = []
        for exp in exps:
            a, b = spans[(i, exp.NAME)]
            mine = results[a:b]
            if ctx is main and exp.NAME in flown:
                lv = flown[exp.NAME]
            elif exp.NAME == "rectangle":
                lv = exp.headless_live(ctx, mine[0])
            else:
                lv = None
            secs.append(exp.analyse(ctx, mine, lv))
        by_ctx.append(secs)
    columns = [PlantRuns(plant, plant, pairs, {c.seed: by_ctx[i] for i, c in enumerate(contexts) if c.airframe == plant})
               for plant in plants]
    sections = by_ctx[0]
    if controller:
        names = list(compared)  # the experiments compared (none named: all of them)
    else:
        names = None if not only else [e.NAME for e in exps] + ([STABILITY] if with_stability else [])
    files = report.write(out, sections, stab_md, stab, seed, quick, names, columns=columns, n_seeds=seeds,
                         controller=controller, strategy=strategy)
    files += [out / name for s in sections for name in s.figures]
    files += [c.out_dir / name for i, c in enumerate(contexts) if i > 0 for s in by_ctx[i] for name in s.figures]
    flown_s = sum(r.sim_time_s for r in results if not isinstance(r, JobFailed))
    return Outcome(files=files, sections=sections, jobs=len(jobs), sim_seconds=flown_s, columns=columns)
