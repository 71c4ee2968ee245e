"""Many independent headless runs, over local processes or a Dask cluster.

A run is described by a small picklable :class:`SimJob` (scenario preset, strategy, seed,
duration, parameter overrides, which logged columns to bring back); :func:`run_jobs` runs
a list of them and returns their results **in job order**::

    from rig_emulator.sweep import SimJob, run_jobs

    jobs = [SimJob("harmonic", "flc", seed=1, duration=20.0, overrides={"guidance.omega": w})
            for w in (0.1, 0.5, 1.0, 2.0)]
    results = run_jobs(jobs)                                   # local processes, one per core
    results = run_jobs(jobs, workers=1)                        # serially, in this process
    results = run_jobs(jobs, scheduler="tcp://10.0.0.5:8786")  # a Dask cluster
    results[0].mean_errors()["phi_deg"], results[0].series["euler"]

Where the runs go:

* ``scheduler`` (``"tcp://host:port"`` or a ``distributed.Client``) - one Dask task per job
  (``pip install 'hilms-sil[cluster]'``; every worker needs hilms-sil installed);
* else ``pool`` (a :class:`SweepPool`), or the process's shared pool of ``workers``
  (default ``os.cpu_count()``) local processes: a ``concurrent.futures.ProcessPoolExecutor``
  started with ``spawn`` (never ``fork``: the caller may run threads) whose workers import
  the simulation and load its compiled step loop once, when they start. The shared pool is
  **kept warm between calls** (a second sweep pays no interpreter start, imports or numba
  cache load; the first call pays them, about 1-3 s a worker) and is shut down at exit, by
  :func:`shutdown_pool`, or when a call asks for another worker count (a call made while
  another thread's sweep runs on it gets a pool of its own for that call). ``with SweepPool(n) as
  pool: run_jobs(jobs, pool=pool)`` gives a pool of its own with a lifetime of its own;
* ``workers=1`` (or a single job): serially in the calling process, no pool.

Jobs go to the workers in batches that shrink towards the end of a sweep (guided
scheduling): the first hold up to :data:`BATCH_RIG_SECONDS` simulated seconds, so short runs
do not pay a round trip each, and the last are single jobs, so no worker idles while
another finishes a long batch.

What comes back: by default a :class:`JobResult` with the logged series named in
``SimJob.columns`` (all of them when ``None``, none with ``()``: the benchmark's many-rigs
runs ask for nothing but the counts). ``reduce=f`` instead returns ``f(job, sim_result)``
computed where the job ran (``f`` must be picklable: a module-level function), so only
what it returns crosses the process or network boundary.

Determinism: a job's result depends on the job only (the seed seeds every random stream,
see docs/explanation/conventions.md), not on the executor, the worker or the order of completion. Runs
on one machine (one numba build) are bit-identical serial, in local processes or on a
local Dask cluster; machines with other CPUs may differ in the last bits (numba compiles
for the host CPU). :meth:`JobResult.digest` fingerprints a result for such comparisons;
``wall_time_s`` is the only field that varies and it is left out of the digest.

Errors: every job's configuration is validated before anything runs (a
:class:`~rig_emulator.config.loader.ConfigError` names the job and the key); a job that
raises while running stops the sweep with :class:`JobFailed` naming it, or, with
``keep_failed=True``, takes that :class:`JobFailed` as its result and the sweep goes on (a
comparison that reports a controller's failure on one experiment and measures the others).
"""

from __future__ import annotations

import atexit
import copy
import hashlib
import math
import multiprocessing
import os
import threading
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from rig_emulator.config.loader import ConfigError, RigConfig, check_config, load_config
from rig_emulator.config.schema import STRATEGIES
from rig_emulator.simulation.log_layout import NAMES as LOG_NAMES

_SERIES = tuple(LOG_NAMES)  # the logged series a job may ask for

Progress = Callable[[int, int, "SimJob"], None]

#: Simulated seconds a batch of jobs sent to a worker holds at most (about 0.1 s of a
#: worker's time at the full-fidelity rig's speed): a 5 s run costs about 10 ms, and the
#: round trip of a task through the pool costs a good part of a millisecond of the caller's.
BATCH_RIG_SECONDS = 60.0


class JobFailed(RuntimeError):
    """A job raised while running; ``job`` is the job, the message carries its error."""

    def __init__(self, job: "SimJob", message: str):
        super().__init__(job, message)  # both in args: the exception pickles across processes
        self.job = job
        self.message = message

    def __str__(self) -> str:
        return f"{self.job.describe()}: {self.message}"


@dataclass(frozen=True)
class SimJob:
    """One headless run: what :func:`rig_emulator.api.simulate` takes, as picklable data.

    ``overrides`` are dotted parameter keys (``{"guidance.omega": 1.2}``), stored as a tuple
    of (key, value) pairs sorted by key; ``columns`` names the logged series to return
    (None: all, ``()``: none); ``label`` is free text for the caller (it does not affect
    the run); ``controller`` names a controller plug-in (``"package.module:Name"``, imported
    by the worker that runs the job; docs/how-to/your-controller.md).
    """

    scenario: str
    strategy: str = "smc-flc"
    seed: int = 0
    duration: float | None = None
    overrides: tuple = ()
    airframe: str = "hilms"
    columns: tuple | None = None
    label: str = ""
    controller: str = ""

    def __post_init__(self):
        if not isinstance(self.scenario, str) or not self.scenario:
            raise ConfigError(f"SimJob scenario {self.scenario!r}: must be a preset name")
        if self.strategy not in STRATEGIES:
            raise ConfigError(f"SimJob strategy {self.strategy!r}: must be one of {', '.join(STRATEGIES)}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"SimJob seed {self.seed!r}: must be an integer >= 0")
        if self.duration is not None:
            if isinstance(self.duration, bool) or not isinstance(self.duration, (int, float)) \
                    or not (math.isfinite(self.duration) and self.duration > 0):
                raise ConfigError(f"SimJob duration {self.duration!r}: must be a number of seconds > 0")
            object.__setattr__(self, "duration", float(self.duration))
        pairs = self.overrides.items() if isinstance(self.overrides, Mapping) else self.overrides
        try:
            pairs = tuple(sorted((str(k), copy.deepcopy(v)) for k, v in pairs))
        except (TypeError, ValueError):
            raise ConfigError("SimJob overrides: must be a mapping (or pairs) of dotted key -> value") from None
        object.__setattr__(self, "overrides", pairs)
        if not isinstance(self.controller, str) or (self.controller and ":" not in self.controller):
            raise ConfigError(f"SimJob controller {self.controller!r}: must be a plug-in name 'package.module:Name' "
                              "(importable where the job runs)")
        if self.columns is not None:
            cols = (self.columns,) if isinstance(self.columns, str) else tuple(self.columns)
            unknown = [c for c in cols if c not in _SERIES]
            if unknown:
                raise ConfigError(f"SimJob columns {unknown}: unknown; choose from {', '.join(_SERIES)}")
            object.__setattr__(self, "columns", cols)

    def describe(self) -> str:
        head = self.label or f"{self.scenario}/{self.strategy}"
        return f"job {head!r} (seed {self.seed})"

    def _flat_overrides(self) -> dict:
        flat = dict(self.overrides)
        flat["control.strategy"] = self.strategy
        flat["sim.seed"] = self.seed
        if self.controller:
            flat["controller.plugin"] = self.controller
        if self.duration is not None:
            flat["sim.duration"] = self.duration
        return flat

    def check(self) -> None:
        """Raise the ConfigError (naming the job) that :meth:`config` would, without building it."""
        try:
            check_config(airframe=self.airframe, scenario=self.scenario, overrides=self._flat_overrides())
        except ConfigError as exc:
            raise ConfigError(f"{self.describe()}: {exc}") from None

    def config(self) -> RigConfig:
        """The validated configuration this job runs (ConfigError naming the job otherwise)."""
        flat = {k: copy.deepcopy(v) for k, v in self._flat_overrides().items()}
        try:
            return load_config(airframe=self.airframe, scenario=self.scenario, overrides=flat)
        except ConfigError as exc:
            raise ConfigError(f"{self.describe()}: {exc}") from None


@dataclass
class JobResult:
    """What one job produced: the requested series and the run's counts."""

    job: SimJob
    series: dict
    reached_t: np.ndarray
    steps: int
    sim_time_s: float
    wall_time_s: float = field(compare=False)  # the only field that depends on the machine's load

    def mean_errors(self, window: tuple[float, float] | None = None) -> dict[str, float]:
        """Eq. 45 (needs the series t, euler, euler_des, pos, pos_des)."""
        from protocol.mean_error import mean_errors

        s = self.series
        missing = [n for n in ("t", "euler", "euler_des", "pos", "pos_des") if n not in s]
        if missing:
            raise KeyError(f"{self.job.describe()}: mean errors need the series {missing}")
        return mean_errors(s["t"], s["euler"], s["euler_des"], s["pos"], s["pos_des"], window)

    def digest(self) -> str:
        """SHA-256 of the job and every returned number (not the wall time)."""
        h = hashlib.sha256(repr(self.job).encode())
        for name in sorted(self.series):
            a = np.ascontiguousarray(self.series[name])
            h.update(name.encode())
            h.update(str(a.dtype).encode() + str(a.shape).encode())
            h.update(a.tobytes())
        h.update(np.ascontiguousarray(self.reached_t).tobytes())
        h.update(f"{self.steps} {self.sim_time_s!r}".encode())
        return h.hexdigest()


def job_result(job: SimJob, sim) -> JobResult:
    """The default reduction: the requested columns of a :class:`~rig_emulator.simulation.run.SimResult`."""
    names = sim.series.keys() if job.columns is None else job.columns
    series = {n: np.array(sim.series[n], copy=True) for n in names}
    return JobResult(job=job, series=series, reached_t=sim.reached_t.copy(), steps=sim.steps,
                     sim_time_s=sim.sim_time_s, wall_time_s=sim.wall_time_s)


def run_job(job: SimJob, reduce: Callable | None = None):
    """Run one job here and now (what every worker calls)."""
    from rig_emulator.simulation.run import Simulation

    cfg = job.config()
    try:
        sim = Simulation(cfg).run()
    except ConfigError as exc:  # found only when the rig is built (e.g. a missing calibration file)
        raise ConfigError(f"{job.describe()}: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - re-raised with the job named
        raise JobFailed(job, f"{type(exc).__name__}: {exc}") from exc
    return (reduce or job_result)(job, sim)


def _run_job_kept(job: SimJob, reduce: Callable | None = None):
    """:func:`run_job`, its :class:`JobFailed` returned instead of raised (``keep_failed``)."""
    try:
        return run_job(job, reduce)
    except JobFailed as exc:
        return exc


def _job_runner(keep_failed: bool) -> Callable:
    """What runs one job, where it runs: :func:`run_job`, or with ``keep_failed`` :func:`_run_job_kept`."""
    return _run_job_kept if keep_failed else run_job


def _mp_context():
    # spawn, not fork (the caller may run threads) nor forkserver (its workers would not be this
    # process's children)
    return multiprocessing.get_context("spawn")


def _warm_worker(compile_helper: bool = True) -> None:
    """A pool worker's start: import the simulation and load (or compile) its step loop by
    running one physics step, so the first job does not pay it. A worker ignores SIGINT: Ctrl-C
    in a terminal reaches the whole process group, and it is the caller's to act on (it stops
    the sweep; the workers finish the batches they hold and stay warm). ``compile_helper``: a cold
    compile may start a helper process (rig_emulator/compile_helper.py); not when the pool's
    workers already take every core."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if not compile_helper:
        from rig_emulator import compile_helper as helper

        os.environ[helper.ENV_SWITCH] = "0"
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.run import Simulation

    # no calibration procedure: the warm-up needs the compiled loop, not a 0.1 s LM fit
    Simulation(load_config(scenario="hover", overrides={"sim.duration": 0.001, "sensors.calibration": "none"})).run()


def _worker_pid() -> int:
    return os.getpid()


def _run_batch(jobs, reduce, keep_failed=False):
    one = _job_runner(keep_failed)
    return [one(job, reduce) for job in jobs]


class SweepPool:
    """Warm local worker processes for :func:`run_jobs` (``pool=``); see the module docstring.

    ``SweepPool(workers)`` starts ``workers`` spawned processes (default ``os.cpu_count()``),
    each loading the compiled step loop; :meth:`close` (or the ``with`` block's end) stops
    them. One sweep at a time runs on a pool. ``pids`` are the workers' process ids (e.g. to
    read their CPU time, which ``getrusage(RUSAGE_CHILDREN)`` shows only once they exit).
    """

    def __init__(self, workers: int | None = None):
        n = (os.cpu_count() or 1) if workers is None else workers
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"workers {workers!r}: must be an integer >= 1")
        self.workers = n
        # workers compiling cold at once already keep the cores busy: no compile helpers then
        self._executor = ProcessPoolExecutor(max_workers=n, mp_context=_mp_context(), initializer=_warm_worker,
                                             initargs=(n < (os.cpu_count() or 1),))
        self._lock = threading.Lock()
        self._broken = False
        # start every worker now (the executor would otherwise start them as work arrives)
        futures = [self._executor.submit(_worker_pid) for _ in range(n)]
        try:
            wait(futures)
            for f in futures:
                f.result()
        except BaseException:
            self.close()
            raise

    @property
    def broken(self) -> bool:
        """A worker died (killed, out of memory, crashed): the pool runs nothing more."""
        return self._broken or bool(getattr(self._executor, "_broken", False))

    @property
    def pids(self) -> list[int]:
        return sorted(self._executor._processes or {})  # noqa: SLF001 - the executor keeps no public list

    def close(self) -> None:
        self._executor.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> "SweepPool":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def run(self, jobs: Sequence[SimJob], progress: Progress | None = None, reduce: Callable | None = None,
            keep_failed: bool = False) -> list:
        """Run validated ``jobs`` on the workers; results in job order (``keep_failed``: see :func:`run_jobs`)."""
        if not self._lock.acquire(blocking=False):
            raise RuntimeError("a sweep is already running on this SweepPool")
        try:
            return self._run(list(jobs), progress, reduce, keep_failed)
        finally:
            self._lock.release()

    def _batch_size(self, remaining: int, job: SimJob) -> int:
        guided = math.ceil(remaining / (2 * self.workers))
        cap = max(1, int(BATCH_RIG_SECONDS // job.duration)) if job.duration else 1
        return max(1, min(guided, cap))

    def _run(self, jobs: list, progress, reduce, keep_failed: bool = False) -> list:
        results: list = [None] * len(jobs)
        pending: dict = {}  # future -> first job index of its batch
        nxt = done_count = 0
        try:
            while nxt < len(jobs) or pending:
                # keep two batches per worker in flight: a worker never waits for the caller
                while nxt < len(jobs) and len(pending) < 2 * self.workers:
                    size = self._batch_size(len(jobs) - nxt, jobs[nxt])
                    try:
                        fut = self._executor.submit(_run_batch, jobs[nxt:nxt + size], reduce, keep_failed)
                    except BrokenProcessPool as exc:
                        raise self._died(jobs[nxt], exc) from exc
                    pending[fut] = nxt
                    nxt += size
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    first = pending.pop(fut)
                    try:
                        batch = fut.result()
                    except BrokenProcessPool as exc:
                        raise self._died(jobs[first], exc) from exc
                    for k, r in enumerate(batch, start=first):
                        results[k] = r
                        done_count += 1
                        if progress is not None:
                            progress(done_count, len(jobs), jobs[k])
        except BaseException:
            for fut in pending:
                fut.cancel()
            wait(pending)  # the workers finish what they hold: the pool stays usable
            raise
        return results

    def _died(self, job: SimJob, exc: BaseException) -> JobFailed:
        self._broken = True
        return JobFailed(job, f"a worker process died while running it or its batch ({exc}); the pool "
                              "is discarded, the next sweep starts new workers")


_shared: SweepPool | None = None
_shared_lock = threading.Lock()


def _run_shared(jobs: list, workers: int, progress, reduce, keep_failed: bool = False) -> list:
    """Run on the shared pool; when another thread's sweep holds it, on a pool of this call's
    own (as before pools were kept), never closing a pool that is running a sweep."""
    global _shared
    with _shared_lock:
        pool = _shared
        if pool is not None and (pool.workers != workers or pool.broken) and not pool._lock.locked():
            pool.close()
            pool = _shared = None
        if pool is None:
            pool = _shared = SweepPool(workers)
        claimed = pool.workers == workers and not pool.broken and pool._lock.acquire(blocking=False)
    if not claimed:
        with SweepPool(workers) as own:
            return own.run(jobs, progress, reduce, keep_failed)
    try:
        return pool._run(jobs, progress, reduce, keep_failed)
    finally:
        pool._lock.release()


def shutdown_pool() -> None:
    """Stop the shared worker processes of :func:`run_jobs` (the next pooled call starts new
    ones); a sweep running on them in another thread finishes first."""
    global _shared
    with _shared_lock:
        pool, _shared = _shared, None
    if pool is not None:
        with pool._lock:  # waits for a sweep running on it
            pool.close()


atexit.register(shutdown_pool)


def run_jobs(jobs: Sequence[SimJob], *, workers: int | None = None, scheduler: Any = None,
             progress: Progress | None = None, reduce: Callable | None = None,
             pool: SweepPool | None = None, keep_failed: bool = False) -> list:
    """Run ``jobs`` and return their results in job order (see the module docstring).

    A job that raises while running stops the sweep with :class:`JobFailed`; with ``keep_failed``
    its :class:`JobFailed` stands in its result's place and the other jobs run on. Bad
    configurations (:class:`~rig_emulator.config.loader.ConfigError`) and a worker that dies
    stop the sweep either way.

    ``progress(done, total, job)`` is called in the calling process after each job finishes
    (in completion order). ``workers`` caps the local processes (default ``os.cpu_count()``);
    ``pool`` runs them on a :class:`SweepPool` of the caller's; ``scheduler`` sends the jobs to
    a Dask cluster instead.
    """
    jobs = list(jobs)
    for job in jobs:
        if not isinstance(job, SimJob):
            raise TypeError(f"run_jobs takes SimJob items, got {type(job).__name__}")
        job.check()  # bad input fails here, before anything runs
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers {workers!r}: must be an integer >= 1")
    if not jobs:
        return []
    if scheduler is not None:
        return _run_dask(jobs, scheduler, progress, reduce, keep_failed)
    if pool is not None:
        return pool.run(jobs, progress, reduce, keep_failed)
    n = workers or os.cpu_count() or 1
    if n == 1 or len(jobs) == 1:
        out = []
        for k, job in enumerate(jobs):
            out.append(_job_runner(keep_failed)(job, reduce))
            if progress is not None:
                progress(k + 1, len(jobs), job)
        return out
    return _run_shared(jobs, n, progress, reduce, keep_failed)


def _run_dask(jobs, scheduler, progress, reduce, keep_failed: bool = False) -> list:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise RuntimeError("running on a Dask cluster needs dask.distributed: pip install 'hilms-sil[cluster]'") from None
    own = not isinstance(scheduler, Client)
    client = Client(scheduler, timeout="30s") if own else scheduler
    try:
        futures = client.map(_job_runner(keep_failed), jobs, reduce=reduce, pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        results: list = [None] * len(jobs)
        for done_count, fut in enumerate(as_completed(futures), start=1):
            k = index[fut.key]
            results[k] = fut.result()
            if progress is not None:
                progress(done_count, len(jobs), jobs[k])
        return results
    finally:
        if own:
            client.close()


def rig_seconds_per_wall_second(results: Sequence, wall_s: float) -> float:
    """Simulated rig-seconds of ``results`` (JobResults) per wall-clock second of the sweep."""
    total = sum(r.sim_time_s for r in results)
    return total / wall_s if wall_s > 0 else math.inf

