"""rig_emulator.sweep: the same jobs give the same numbers serially, in local processes and on
a local Dask cluster (two worker processes); bad jobs fail before anything runs."""

import numpy as np
import pytest

from rig_emulator.config.loader import ConfigError
from rig_emulator.sweep import JobResult, SimJob, run_jobs

COLUMNS = ("t", "euler", "euler_des", "pos", "pos_des", "v_cmd")


def _jobs():
    return [SimJob("harmonic", s, seed=3, duration=1.0, overrides={"guidance.omega": w}, columns=COLUMNS,
                   label=f"{s}/{w}") for s, w in (("flc", 0.5), ("smc", 1.5), ("flc", 2.0))]


def _summary(job, sim):  # a reduction computed where the job ran (module level: picklable)
    return job.label, float(np.abs(sim.series["euler"] - sim.series["euler_des"]).sum())


@pytest.fixture(scope="module")
def serial():
    seen = []
    results = run_jobs(_jobs(), workers=1, progress=lambda done, total, job: seen.append((done, total, job.label)))
    return results, seen


def test_serial_results_in_job_order_with_progress(serial):
    results, seen = serial
    assert [r.job.label for r in results] == [j.label for j in _jobs()]
    assert seen == [(1, 3, "flc/0.5"), (2, 3, "smc/1.5"), (3, 3, "flc/2.0")]
    r = results[0]
    assert isinstance(r, JobResult) and set(r.series) == set(COLUMNS)
    assert r.series["t"].shape == (100,) and r.steps == 1000 and r.sim_time_s == 1.0
    assert r.mean_errors()["phi_deg"] > 0.0
    assert len({x.digest() for x in results}) == 3  # different jobs, different numbers


def _assert_same(a, b):
    assert [x.digest() for x in a] == [x.digest() for x in b]
    for x, y in zip(a, b):
        for name in COLUMNS:
            assert np.array_equal(x.series[name], y.series[name], equal_nan=True)


def test_local_processes_give_the_serial_numbers(serial):
    seen = []
    pooled = run_jobs(_jobs(), workers=2, progress=lambda done, total, job: seen.append(done))
    _assert_same(serial[0], pooled)
    assert seen == [1, 2, 3]


def test_local_dask_cluster_gives_the_serial_numbers(serial):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            on_dask = run_jobs(_jobs(), scheduler=cluster.scheduler_address)
            assert len(client.scheduler_info()["workers"]) == 2
            reduced = run_jobs(_jobs()[:2], scheduler=client, reduce=_summary)
    _assert_same(serial[0], on_dask)
    assert reduced == [_summary(j, _Sim(r)) for j, r in zip(_jobs()[:2], serial[0][:2])]


class _Sim:  # the reduction's view of a result (series only)
    def __init__(self, result):
        self.series = result.series


def test_empty_series_selection_and_reduce_in_process():
    job = SimJob("hover", "pid", seed=0, duration=0.2, columns=())
    (r,) = run_jobs([job], workers=1)
    assert r.series == {} and r.steps == 200
    assert run_jobs([job], workers=1, reduce=lambda j, sim: (j.strategy, sim.steps)) == [("pid", 200)]


def test_bad_jobs_fail_before_anything_runs():
    with pytest.raises(ConfigError, match="strategy 'fuzzy'"):
        SimJob("hover", "fuzzy")
    with pytest.raises(ConfigError, match="duration"):
        SimJob("hover", duration=-1.0)
    with pytest.raises(ConfigError, match="columns"):
        SimJob("hover", columns=("nope",))
    ran = []
    jobs = [SimJob("hover", duration=0.1), SimJob("hover", duration=0.1, overrides={"guidance.omega": -2.0},
                                                  label="bad omega")]
    with pytest.raises(ConfigError, match="bad omega.*guidance.omega"):
        run_jobs(jobs, workers=1, progress=lambda *a: ran.append(a))
    assert ran == []
    with pytest.raises(ConfigError, match="unknown scenario"):
        run_jobs([SimJob("no-such-scenario")], workers=1)
    missing = SimJob("hover", duration=0.1, overrides={"sensors.calibration_file": "/nonexistent/cal.json"},
                     label="no calibration")
    with pytest.raises(ConfigError, match="no calibration.*calibration file not found"):
        run_jobs([missing], workers=1)  # found when the rig is built: still names the job
    with pytest.raises(ValueError, match="workers"):
        run_jobs(jobs[:1], workers=0)
    assert run_jobs([], workers=2) == []


def _die_on_label_x(job, sim):  # a reduction that kills its worker (module level: picklable)
    import os
    import signal

    if job.label == "x":
        os.kill(os.getpid(), signal.SIGKILL)
    return job.label


def test_run_jobs_keeps_its_warm_pool_between_calls_and_replaces_a_broken_one():
    import os
    import signal
    import time

    from rig_emulator import sweep

    jobs = [SimJob("hover", "pid", seed=1, duration=0.2, columns=(), label=str(k)) for k in range(4)]
    first = run_jobs(jobs, workers=2)
    pool = sweep._shared
    assert pool is not None and pool.workers == 2 and len(pool.pids) == 2
    again = run_jobs(jobs, workers=2)
    assert sweep._shared is pool and pool.pids == sweep._shared.pids  # the same warm workers
    assert [r.digest() for r in first] == [r.digest() for r in again]
    # a worker dies while it runs a job (killed, out of memory, ...): the sweep fails naming it
    doomed = jobs[:2] + [SimJob("hover", "pid", seed=1, duration=0.2, columns=(), label="x")]
    with pytest.raises(sweep.JobFailed, match="worker process died"):
        run_jobs(doomed, workers=2, reduce=_die_on_label_x)
    assert pool.broken
    after = run_jobs(jobs, workers=2)  # a new pool
    assert sweep._shared is not pool and [r.digest() for r in after] == [r.digest() for r in first]
    # a worker that dies between sweeps: the next call notices and starts a new pool
    idle = sweep._shared
    os.kill(idle.pids[0], signal.SIGKILL)
    deadline = time.monotonic() + 20
    while not idle.broken and time.monotonic() < deadline:
        time.sleep(0.05)
    assert idle.broken
    assert [r.digest() for r in run_jobs(jobs, workers=2)] == [r.digest() for r in first]
    assert sweep._shared is not idle
    sweep.shutdown_pool()
    assert sweep._shared is None


def test_a_pool_of_ones_own_and_guided_batches():
    from rig_emulator.sweep import SweepPool

    jobs = [SimJob("hover", "pid", seed=2, duration=0.1, columns=(), label=str(k)) for k in range(9)]
    seen = []
    with SweepPool(2) as pool:
        out = run_jobs(jobs, pool=pool, progress=lambda done, total, job: seen.append((done, total)))
        assert [r.job.label for r in out] == [j.label for j in jobs]
        assert seen == [(k, 9) for k in range(1, 10)]
        sizes = []
        left = 9
        while left:
            sizes.append(pool._batch_size(left, jobs[0]))
            left -= sizes[-1]
        assert sizes[-1] == 1 and sizes == sorted(sizes, reverse=True)  # shrinking to single jobs
    with pytest.raises(ValueError, match="workers 0"):
        SweepPool(0)


def test_sweeps_from_two_threads_at_once_both_complete():
    import threading

    from rig_emulator import sweep

    jobs = [SimJob("hover", "pid", seed=3, duration=0.5, columns=(), label=str(k)) for k in range(6)]
    expected = [r.digest() for r in run_jobs(jobs, workers=1)]
    got, errors = {}, []

    def go(name):
        try:
            got[name] = [r.digest() for r in run_jobs(jobs, workers=2)]
        except Exception as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=go, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors and got == {0: expected, 1: expected}
    sweep.shutdown_pool()


@pytest.mark.parametrize("workers", [1, 2])
def test_keep_failed_puts_a_raising_job_failure_in_its_place_and_runs_the_rest(workers):
    from rig_emulator.sweep import JobFailed

    raises = SimJob("hover", seed=1, duration=4.0, columns=(), label="raises",
                    controller="tests.rig_emulator.controllers.test_plugin_errors:RaisesAt3")
    fine = [SimJob("hover", "pid", seed=1, duration=0.2, columns=(), label=str(k)) for k in range(2)]
    with pytest.raises(JobFailed, match="raises.*my gain schedule divided by zero"):
        run_jobs([fine[0], raises, fine[1]], workers=workers)
    got = run_jobs([fine[0], raises, fine[1]], workers=workers, keep_failed=True)
    assert isinstance(got[1], JobFailed) and got[1].job == raises and "divided by zero" in got[1].message
    assert [r.digest() for r in (got[0], got[2])] == [r.digest() for r in run_jobs(fine, workers=1)]
