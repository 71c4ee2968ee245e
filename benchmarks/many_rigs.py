"""many-rigs: sweeps of N = 10, 100, 1000 independent rigs over all cores.

The rigs. Every rig is the full-fidelity rig of ``rig-core`` (1 kHz physics, five IMU
modules, four load cells, estimators, smc-flc) flying the harmonic attitude reference of
Eq. 44 (Fig. 13) for ``duration`` simulated seconds (5 s; quick: 1 s), each with its own
frequency ``guidance.omega`` spread over 0.2 .. 2.0 rad/s. They are one physical rig
(``sim.seed = 0``) whose IMU calibration (Sec. 4-1) is run once by the probe, before any
timing, with ``rig-emulator calibrate`` and loaded by every run
(``sensors.calibration_file``), as the real rig is calibrated once and then flown many
times. (Rigs of distinct seeds would each run the calibration procedure at start-up;
``sweep-single`` reports what that costs per rig.) Each run asks for no time series back
(``SimJob.columns = ()``).

Probes (fresh processes, numba cache warm):

* ``sweep-single`` - ``jobs`` of those runs one after another in one warm process
  (``run_jobs(workers=1)``): the single-rig real-time factor (simulated s / s in the
  compiled loop, median over the runs: item 1's figure for this scenario), the serial
  end-to-end throughput (simulated s per wall s including each run's configuration and
  set-up), the set-up time per run, and the start-up of one rig that runs the calibration
  procedure itself.
* ``sweep-n10``, ``sweep-n100``, ``sweep-n1000`` - :func:`rig_emulator.sweep.run_jobs` over
  a :class:`~rig_emulator.sweep.SweepPool` of ``os.cpu_count()`` local worker processes,
  twice: the **cold** sweep counts the pool's start (spawn, imports, numba cache load in
  each worker) in its wall time, as the first sweep of a fresh process; the **warm** sweep
  runs the same jobs again on the started pool, as every later sweep of a session
  (``run_jobs`` keeps its pool between calls). Aggregate rig-seconds per wall second
  (validation, batching, runs, results), and CPU seconds of this process and its workers
  (``/proc/PID/stat``), which do not depend on what else the machine runs.

Figures. **Parallel efficiency** (the issue's) = aggregate rig-s per wall s of the warm
sweeps / (single-rig real-time factor x cores), with the single-rig figure measured next to
the sweeps, in the sweep's own process (the same runs one after another, just before and
just after them); target >= 80 %. This machine's speed changes by up to 1.8x from one
second to the next (other tenants of the host: a rig's 5 s run takes 5 ms in one stretch
and 9 ms in the next), so a reference measured in another process at another time (the
``sweep-single`` probe; that ratio is shown too) says as much about the host as about the
sweep; ``reference after / before`` shows how much the speed moved during the sweeps. The
efficiency counts wall time, so whatever else runs on the machine lowers it. Beside it, the
**CPU efficiency** (the caller's ``process_time`` and the workers' ``/proc`` counters) =
rig-s per CPU-s of the sweeps / the reference runs' rig-s per CPU-s: the share of the
sweeps' CPU time that simulates (1 - what set-up, batching and result traffic cost), which
other load does not change; and the cores the sweeps kept busy (CPU s / wall s).

BLAS threads. Both probes run with one BLAS thread per process (``OPENBLAS_NUM_THREADS=1``,
inherited by the workers): with OpenBLAS's default of one thread per core, a rig's set-up
(scipy's DARE solve for the load-cell Kalman gain) cost about three times the CPU on this
machine, and the workers already occupy every core.

Dask. With ``python -m benchmarks --scheduler ADDRESS`` (``tcp://host:8786``, or ``local``
for a ``distributed.LocalCluster`` with one single-threaded worker process per core started
by the probe) the N-rig probes also run each sweep on that cluster and report the same
figures against its total thread count. A remote cluster's workers must have hilms-sil
installed and see the calibration file at the same path (a shared file system).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

from . import procfs
from .harness import REGISTRY, BenchmarkError, Metric, ProbeStats, Target, benchmark, median, probe

SINGLE_PROBE = "sweep-single"
SIZES = (10, 100, 1000)
QUICK_SIZES = {10: 4, 100: 8, 1000: 16}
CACHE_GROUP = "served-rig"
SCENARIO = "harmonic"
STRATEGY = "smc-flc"
SEED = 0
DURATION_S = 5.0
QUICK_DURATION_S = 1.0
OMEGA_RANGE = (0.2, 2.0)
SCHEDULER_ENV = "HILMS_BENCH_SCHEDULER"
EFFICIENCY_TARGET = Target(">=", 0.8, "parallel efficiency")
#: One BLAS thread per process: the workers are as many as the cores already, and OpenBLAS's
#: own threads (one per core, spinning while they wait) tripled the CPU cost of a rig's
#: set-up (the load-cell Kalman gain's DARE solve) on this 2-core machine.
SINGLE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def single_threaded_blas() -> None:
    """Set :data:`SINGLE_THREAD_ENV` in this process's environment (before numpy is imported
    here, and for every worker process spawned from now on)."""
    os.environ.update(SINGLE_THREAD_ENV)


def probe_name(n: int) -> str:
    return f"sweep-n{n}"


def _sweep():
    from .harness import BenchmarkUnavailable

    try:
        from rig_emulator import sweep
    except ImportError as exc:
        raise BenchmarkUnavailable(f"rig_emulator.sweep is not importable: {type(exc).__name__}: {exc}") from None
    for name in ("SimJob", "run_jobs"):
        if not hasattr(sweep, name):
            raise BenchmarkUnavailable(f"rig_emulator.sweep has no {name}: the many-rigs benchmark needs it")
    return sweep


def make_calibration(directory: str) -> str:
    """Run ``rig-emulator calibrate --seed SEED`` into ``directory``; returns the file's path."""
    path = os.path.join(directory, f"imu-calibration-seed{SEED}.json")
    proc = subprocess.run([sys.executable, "-m", "rig_emulator", "calibrate", "--seed", str(SEED), "--out", path],
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0 or not os.path.exists(path):
        raise RuntimeError(f"rig-emulator calibrate failed ({proc.returncode}): {proc.stderr.strip()[-500:]}")
    return path


def omegas(n: int) -> list[float]:
    lo, hi = OMEGA_RANGE
    return [lo + (hi - lo) * k / max(n - 1, 1) for k in range(n)]


def make_jobs(n: int, duration: float, calibration_file: str | None):
    """``n`` harmonic runs of the seed-0 rig, one ``guidance.omega`` each, no series returned."""
    sweep = _sweep()
    base = {"sensors.calibration_file": calibration_file} if calibration_file else {}
    return [sweep.SimJob(SCENARIO, STRATEGY, seed=SEED, duration=duration, columns=(),
                         overrides={**base, "guidance.omega": w}, label=f"omega={w:.4f}")
            for w in omegas(n)]


def _figures(results, wall: float, cpu: float | None, cores: int, prefix: str) -> dict:
    sim = sum(r.sim_time_s for r in results)
    figs = {f"{prefix}rig_s_per_wall_s": sim / wall, f"{prefix}wall_s": wall, f"{prefix}cores": cores,
            f"{prefix}rig_s": sim}
    if cpu is not None:
        figs[f"{prefix}cpu_s"] = cpu
        figs[f"{prefix}rig_s_per_cpu_s"] = sim / cpu
        figs[f"{prefix}cores_used"] = cpu / wall
    return figs


@probe(SINGLE_PROBE, params={"jobs": 10, "duration": DURATION_S}, quick={"jobs": 3, "duration": QUICK_DURATION_S},
       cache=CACHE_GROUP, description=f"{SCENARIO} runs one after another in one warm process (the single-rig figure)")
def sweep_single_probe(jobs: int, duration: float) -> dict:
    """Single-rig real-time factor and serial throughput of the sweep's runs; see the module docstring.

    Each run is what ``rig_emulator.sweep.run_job`` does (``Simulation(job.config()).run()``),
    timed in two parts: set-up (configuration + construction) and the run, in wall and CPU
    seconds of this process.
    """
    import pickle

    single_threaded_blas()
    c0 = time.process_time()
    sweep = _sweep()
    from rig_emulator.simulation.run import Simulation

    import_cpu_s = time.process_time() - c0

    with tempfile.TemporaryDirectory(prefix="hilms-bench-sweep-") as tmp:
        t0 = time.perf_counter()
        cal = make_calibration(tmp)
        calibrate_s = time.perf_counter() - t0
        batch = make_jobs(jobs, duration, cal)
        c0 = time.process_time()
        warm = sweep.run_jobs(batch[:1], workers=1)  # loads (or compiles) the step loop
        first_run_cpu_s = time.process_time() - c0
        setup_w = setup_c = run_w = run_c = sim = 0.0
        rtfs = []
        for job in batch:
            w0, c0 = time.perf_counter(), time.process_time()
            rig = Simulation(job.config())
            w1, c1 = time.perf_counter(), time.process_time()
            r = rig.run()
            w2, c2 = time.perf_counter(), time.process_time()
            setup_w += w1 - w0
            setup_c += c1 - c0
            run_w += w2 - w1
            run_c += c2 - c1
            sim += r.sim_time_s
            rtfs.append(r.sim_time_s / r.wall_time_s)
        # a rig that runs the calibration procedure itself at start-up (scipy's optimiser imported
        # first: a worker imports it once, for its first such rig)
        import scipy.optimize  # noqa: F401

        own = sweep.SimJob(SCENARIO, STRATEGY, seed=SEED, duration=duration, columns=())
        w0, c0 = time.perf_counter(), time.process_time()
        Simulation(own.config())
        own_w, own_c = time.perf_counter() - w0, time.process_time() - c0
    n = len(batch)
    return {
        "rtf": median(rtfs),
        "rtf_cpu": sim / run_c,
        "serial_rig_s_per_wall_s": sim / (setup_w + run_w),
        "serial_rig_s_per_cpu_s": sim / (setup_c + run_c),
        "setup_s_per_rig": setup_w / n,
        "setup_cpu_s_per_rig": setup_c / n,
        "run_cpu_s_per_rig": run_c / n,
        "setup_s_per_rig_calibrating": own_w,
        "setup_cpu_s_per_rig_calibrating": own_c,
        "calibrate_cli_s": calibrate_s,
        "import_cpu_s": import_cpu_s,
        "first_run_cpu_s": first_run_cpu_s,
        "result_bytes": len(pickle.dumps(warm[0])),
        "duration_s": duration,
        "jobs": n,
    }


def _local_cluster(cores: int):
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=cores, threads_per_worker=1, processes=True, dashboard_address=None)
    return cluster, Client(cluster)


def _dask_sweep(batch, address: str, cores_local: int) -> dict:
    sweep = _sweep()
    try:
        from distributed import Client
    except ImportError:
        raise RuntimeError(f"{SCHEDULER_ENV}={address!r} needs dask.distributed (pip install 'hilms-sil[cluster]')") \
            from None
    cluster = None
    t_setup = time.perf_counter()
    if address == "local":
        cluster, client = _local_cluster(cores_local)
    else:
        client = Client(address, timeout="30s")
    try:
        setup_s = time.perf_counter() - t_setup
        threads = sum(client.nthreads().values())
        t0 = time.perf_counter()
        results = sweep.run_jobs(batch, scheduler=client)
        wall = time.perf_counter() - t0
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    figs = _figures(results, wall, None, threads, "dask_")
    figs["dask_cluster_setup_s"] = setup_s
    return figs


def _pool_cpu(pids) -> float:
    return sum(procfs.cpu_seconds(pid) for pid in pids)


#: Runs of the single-rig reference taken in the sweep's own process, just before and just after
#: the warm sweeps (so the reference and the sweep see the machine in the same state).
ADJACENT_REFERENCE_RUNS = 10
#: Warm sweeps repeat until they have taken this long (a sweep of 10 rigs takes about 50 ms).
MIN_WARM_WALL_S = 1.0


def _adjacent_reference(sweep, jobs) -> tuple[list[float], float, float]:
    """Single-rig real-time factors of ``jobs`` run one after another in this process (compiled
    loop, wall), plus their simulated seconds and the CPU seconds of those runs."""
    from rig_emulator.simulation.run import Simulation

    rtfs, sim, cpu = [], 0.0, 0.0
    for job in jobs:
        rig = Simulation(job.config())
        c0 = time.process_time()
        r = rig.run()
        cpu += time.process_time() - c0
        sim += r.sim_time_s
        rtfs.append(r.sim_time_s / r.wall_time_s)
    return rtfs, sim, cpu


def sweep_probe(n: int, duration: float) -> dict:
    """``n`` runs over all local cores with ``rig_emulator.sweep.run_jobs`` (and a Dask cluster if given).

    Two timings. **Cold**: the first sweep of a fresh process, the pool's start included
    (``SweepPool``: spawn, imports, numba cache load in each worker). **Warm**: the same
    sweep again on the started pool, as every sweep after the first in a session, a
    notebook or a long-lived script (``run_jobs`` keeps its pool between calls), repeated
    until :data:`MIN_WARM_WALL_S` has passed. The **adjacent reference**: the single-rig
    real-time factor of :data:`ADJACENT_REFERENCE_RUNS` of the same runs, one after another in
    this process, just before and just after the warm sweeps. CPU time: this process
    (``process_time``) and each worker's (``/proc/PID/stat``), sampled around each part.
    """
    single_threaded_blas()
    sweep = _sweep()
    if not hasattr(sweep, "SweepPool"):
        from .harness import BenchmarkUnavailable

        raise BenchmarkUnavailable("rig_emulator.sweep has no SweepPool")
    cores = os.cpu_count() or 1
    with tempfile.TemporaryDirectory(prefix="hilms-bench-sweep-") as tmp:
        cal = make_calibration(tmp)
        batch = make_jobs(n, duration, cal)
        ref_jobs = [batch[k * len(batch) // ADJACENT_REFERENCE_RUNS] for k in range(ADJACENT_REFERENCE_RUNS)]
        _adjacent_reference(sweep, ref_jobs[:1])  # loads the step loop in this process
        load = procfs.MachineLoad().start()
        c0 = time.process_time()
        t0 = time.perf_counter()
        pool = sweep.SweepPool(cores)
        try:
            start_wall = time.perf_counter() - t0
            start_cpu = (time.process_time() - c0) + _pool_cpu(pool.pids)
            figs = {"pool_start_s": start_wall, "pool_start_cpu_s": start_cpu}
            w_cpu0, p_cpu0 = _pool_cpu(pool.pids), time.process_time()
            t0 = time.perf_counter()
            results = sweep.run_jobs(batch, pool=pool)
            wall = time.perf_counter() - t0
            cpu = time.process_time() - p_cpu0 + _pool_cpu(pool.pids) - w_cpu0
            if len(results) != n or any(r.sim_time_s <= 0 for r in results):
                raise RuntimeError(f"the sweep returned {len(results)} results for {n} jobs")
            figs.update(_figures(results, wall + start_wall, cpu + start_cpu, cores, "cold_"))

            ref_rtfs, ref_sim, ref_cpu = _adjacent_reference(sweep, ref_jobs)
            w_cpu0, p_cpu0 = _pool_cpu(pool.pids), time.process_time()
            t0 = time.perf_counter()
            warm, sweeps = [], 0
            while not sweeps or time.perf_counter() - t0 < MIN_WARM_WALL_S:
                warm += sweep.run_jobs(batch, pool=pool)
                sweeps += 1
            wall = time.perf_counter() - t0
            parent = time.process_time() - p_cpu0
            workers = _pool_cpu(pool.pids) - w_cpu0
            after_rtfs, after_sim, after_cpu = _adjacent_reference(sweep, ref_jobs)
            figs.update(_figures(warm, wall, parent + workers, cores, ""))
            figs["parent_cpu_s"] = parent / sweeps
            figs["warm_sweeps"] = sweeps
            figs["ref_rtf"] = median(ref_rtfs + after_rtfs)
            figs["ref_rtf_cpu"] = (ref_sim + after_sim) / (ref_cpu + after_cpu)
            figs["ref_drift"] = median(after_rtfs) / median(ref_rtfs)
        finally:
            pool.close()
        load.stop()
        figs["n"] = n
        figs["duration_s"] = duration
        figs.update(load.figures())
        address = os.environ.get(SCHEDULER_ENV)
        if address:
            figs.update(_dask_sweep(batch, address, cores))
            figs["dask_scheduler"] = address
    return figs


for _n in SIZES:
    REGISTRY.add_probe(probe_name(_n), sweep_probe, params={"n": _n, "duration": DURATION_S},
                        quick={"n": QUICK_SIZES[_n], "duration": QUICK_DURATION_S}, cache=CACHE_GROUP,
                        description=f"{_n} {SCENARIO} runs over all cores (rig_emulator.sweep.run_jobs)")


def _per_rep(num: ProbeStats, key: str, single: ProbeStats, ref_key: str, scale_key: str | None) -> list[float]:
    a, b = num.values(key), single.values(ref_key)
    if len(a) != len(b) or not a:
        raise BenchmarkError(f"cannot pair {num.name!r} ({len(a)} runs) with {single.name!r} ({len(b)} runs)")
    scale = num.values(scale_key) if scale_key else [1.0] * len(a)
    return [x / (y * c) for x, y, c in zip(a, b, scale)]


def _own(s: ProbeStats, key: str, ref_key: str, scale_key: str | None) -> list[float]:
    """``key / (ref_key x scale_key)`` within each run of one probe."""
    return [r[key] / (r[ref_key] * (r[scale_key] if scale_key else 1.0)) for r in s.runs]


def _ratio(name: str, values: list[float], reference: str, unit: str = "x", targets=(), note: str = "") -> Metric:
    return Metric(name, median(values), unit, reference, tuple(targets), min(values), max(values), note)


@benchmark("many-rigs", probes=(SINGLE_PROBE,) + tuple(probe_name(n) for n in SIZES),
           description="sweeps of 10, 100, 1000 rigs over all cores (and a Dask cluster if given): "
                       "rig-s per wall s vs the single-rig figure x cores")
def many_rigs(stats: dict[str, ProbeStats]) -> list[Metric]:
    single = stats[SINGLE_PROBE]
    out = [
        single.metric("rtf", "single rig: real-time factor (compiled loop, wall)", "x real time",
                      note=f"{SCENARIO} {single.runs[0].get('duration_s', DURATION_S):g} s, full fidelity, runs one "
                           "after another in a warm process; the reference of the parallel efficiency"),
        single.metric("rtf_cpu", "single rig: simulated s per CPU s of the run", "x real time",
                      note="the same runs counted in CPU time: the reference of the CPU efficiency"),
        single.metric("serial_rig_s_per_wall_s", "single rig: serial end-to-end rig-s per wall s", "rig-s/s",
                      note="configuration and construction of each run included"),
        single.metric("setup_cpu_s_per_rig", "set-up CPU per run (configuration, construction)", "s"),
        single.metric("run_cpu_s_per_rig", "run CPU per run (the simulated seconds)", "s"),
        single.metric("setup_cpu_s_per_rig_calibrating", "set-up CPU per run that runs the IMU calibration", "s",
                      note="what each rig of a distinct seed pays at start-up (the benchmark's rigs load one "
                           "stored calibration)"),
        single.metric("import_cpu_s", "fresh process: CPU to import rig_emulator.sweep and the simulation", "s",
                      note="what each sweep worker pays before its first rig"),
        single.metric("first_run_cpu_s", "fresh process: CPU of the first run (numba cache load + one rig)", "s",
                      skip_first=len(single.runs) > 1,
                      note="repetitions after the first (the first may compile)"),
        single.metric("result_bytes", "result sent back per rig (pickled JobResult, no series)", "bytes"),
    ]
    dask = all("dask_rig_s_per_wall_s" in r for n in SIZES for r in stats[probe_name(n)].runs)
    for n in SIZES:
        s = stats[probe_name(n)]
        label = f"N={s.runs[0].get('n', n)}"
        out += [
            s.metric("rig_s_per_wall_s", f"{label}: aggregate rig-s per wall s (warm pool)", "rig-s/s"),
            s.metric("ref_rtf", f"{label}: single rig's real-time factor next to the sweep", "x real time",
                     note="the same runs one after another in the sweep's process, just before and after the warm "
                          "sweeps: the reference of the efficiencies below"),
            _ratio(f"{label}: parallel efficiency (warm pool)", _own(s, "rig_s_per_wall_s", "ref_rtf", "cores"),
                   probe_name(n), targets=(EFFICIENCY_TARGET,),
                   note="aggregate rig-s per wall s / (single-rig real-time factor next to the sweep x cores); "
                        "sweeps on run_jobs' started pool (every sweep of a session after its first)"),
            _ratio(f"{label}: parallel efficiency (warm) vs the sweep-single probe",
                   _per_rep(s, "rig_s_per_wall_s", single, "rtf", "cores"), SINGLE_PROBE,
                   note="the same against the single-rig probe's figure, measured in another process at another "
                        "time, paired by repetition: it also carries the machine's speed changing in between"),
            _ratio(f"{label}: parallel efficiency (cold, pool start included)",
                   _own(s, "cold_rig_s_per_wall_s", "ref_rtf", "cores"), probe_name(n),
                   note="the first sweep of a fresh process: the workers' start (spawn, imports, numba cache "
                        "load) counted in the sweep's wall time"),
            s.metric("pool_start_s", f"{label}: pool start (workers spawned and warm)", "s"),
            _ratio(f"{label}: CPU efficiency (warm)", _own(s, "rig_s_per_cpu_s", "ref_rtf_cpu", None), probe_name(n),
                   note="rig-s per CPU-s of the warm sweeps (caller + workers) / the reference runs' rig-s per CPU-s: "
                        "the share of the sweep's CPU time that simulates; independent of other load"),
            s.metric("ref_drift", f"{label}: reference after / before the warm sweeps", "x",
                     note="how much the machine's speed changed while the sweeps ran (1: not at all)"),
            s.metric("cores_used", f"{label}: cores the sweep kept busy", "cores",
                     note="CPU s of caller + workers / wall s: below the core count when other work shares them"),
            s.metric("wall_s", f"{label}: warm sweeps' wall time", "s"),
            s.metric("warm_sweeps", f"{label}: warm sweeps timed", "sweeps",
                     note=f"repeated until {MIN_WARM_WALL_S:g} s had passed"),
            s.metric("parent_cpu_s", f"{label}: CPU time of the calling process per sweep", "s",
                     note="job checks, batching, result collection"),
            s.metric("machine_busy_cores", f"{label}: machine load during the probe (all processes)", "cores"),
        ]
        if dask:
            out += [
                s.metric("dask_rig_s_per_wall_s", f"{label} on Dask: aggregate rig-s per wall s", "rig-s/s",
                         note=f"scheduler {s.runs[0].get('dask_scheduler')}"),
                _ratio(f"{label} on Dask: parallel efficiency",
                       _own(s, "dask_rig_s_per_wall_s", "ref_rtf", "dask_cores"), probe_name(n),
                       targets=(EFFICIENCY_TARGET,), note="against the cluster's total threads (cold: a sweep "
                                                          "whose jobs the cluster's workers meet for the first time)"),
            ]
    return out
