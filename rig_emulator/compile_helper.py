"""A second process compiling part of the step loop's call tree while this one compiles the rest.

numba compiles under one global lock, so a cold compile of the step loop keeps one core busy
(docs/explanation/performance.md "Cold compile"). But numba's on-disk cache
(:mod:`rig_emulator._jit`) is shared between processes, and when numba types a call from
the loop it first looks for the callee's signature in that cache: a callee compiled by
another process is loaded (and its code linked into the loop's module, as for one compiled
here), not compiled again. So when :func:`split_compile` finds the step loop missing from
the cache it starts a **helper process** that compiles independent subtrees of the loop's
call tree (:func:`loop_jobs`: the rigid body's callees, the log row, the supervisor, the controller's
turn, guidance, the load-cell filter, the attitude estimation) into the cache while this process types the loop
and compiles the rest.

The two share the jobs through claim files (``os.open(..., O_CREAT | O_EXCL)`` in a private
directory): whoever claims a job compiles it. The helper takes the jobs in the reverse of the
order the loop's typing reaches them; when this process reaches a job's call, it claims it
and compiles it itself if the helper has not started it, else waits for the helper's "done"
file and then loads the helper's result from the cache. If the helper has died, fails a job or
produces nothing the cache can use (another signature), numba simply compiles the callee here:
the split changes where a callee is compiled, never what is compiled (the loop's machine code
is the same but for the callees' symbol names; headless logs stay bit-identical).

There is no helper when the cache holds the loop (a warm start) or cannot be read as expected (a
numba upgrade that moved its internals), when a compiled function does
not cache, when no core is idle (a helper sharing this process's core only slows it down), inside
a sweep's pool worker that shares the machine with its siblings (:mod:`rig_emulator.sweep`), or
with ``HILMS_COMPILE_HELPER=0`` in the environment (``1``: whether a core is idle or not).
"""

from __future__ import annotations

import importlib
import inspect
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from numba.core import sigutils

from rig_emulator import _jit

ENV_SWITCH = "HILMS_COMPILE_HELPER"
#: the longest this process waits for one job the helper is compiling before it gives the helper
#: up and compiles the job itself (a hang guard: a job takes seconds, under load tens of seconds)
HANG_GUARD_S = 300.0
_POLL_S = 0.005
_ROOT = str(Path(__file__).resolve().parent.parent)  # the directory the helper imports rig_emulator from


def enabled() -> bool:
    """``HILMS_COMPILE_HELPER``: ``0`` never starts a helper, ``1`` always (when there is work for it),
    anything else (the default) when a core besides this process's own is idle (:func:`idle_cores`)."""
    mode = os.environ.get(ENV_SWITCH, "")
    if mode in ("0", "1"):
        return mode == "1"
    return idle_cores() - 1.0 >= MIN_SPARE_CORES  # one idle core is this process's own (it sleeps in the sample)


#: a helper needs a core of its own: on a busy machine it only takes time from this process (and its
#: start, about 0.6 s CPU of imports, and the callees both compile are lost: +2-3 s with one other busy
#: process on 2 cores, against -7 to -8 s on a quiet machine, so only a clearly busy machine goes without)
MIN_SPARE_CORES = 0.3
_SAMPLE_S = 0.2  # /proc/stat counts in 10 ms ticks; long enough not to follow a blip


def idle_cores(sample_s: float = _SAMPLE_S) -> float:
    """How many of this process's cores are idle now, its own included (it sleeps while it samples): the
    idle share of all CPU time over ``sample_s`` (/proc/stat) times the cores, or the cores minus the
    1-minute load average where there is no /proc/stat."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    try:
        def sample():
            with open("/proc/stat") as fh:
                v = [int(x) for x in fh.readline().split()[1:]]
            return v[3] + v[4], sum(v[:8])  # idle + iowait, all but guest time (counted in user)

        idle0, total0 = sample()
        time.sleep(sample_s)
        idle1, total1 = sample()
        machine = os.cpu_count() or cores
        return min(cores, (idle1 - idle0) / max(1, total1 - total0) * machine)
    except (OSError, ValueError, IndexError):
        return cores - os.getloadavg()[0]


def _key(sig) -> tuple:
    args, _ = sigutils.normalize_signature(sig)
    return tuple(args)


def is_cached(dispatcher, sig) -> bool | None:
    """Whether numba's on-disk cache holds ``dispatcher`` compiled for ``sig``; None when it cannot tell
    (no cache, or numba's cache internals are not what this expects)."""
    try:
        cache = dispatcher._cache
        key = cache._index_key(_key(sig), dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - a NullCache (no caching) or moved internals
        return None


def loop_jobs(args: tuple) -> list:
    """The helper's share of the step loop's call tree for the loop's arguments ``args``: (dispatcher,
    signature) pairs, the controller's turn and the built-in strategy's stages first (the longest piece),
    then the rest in the reverse of the order the loop's typing reaches them. Each signature is
    numba's type of a value of the kind the loop passes (a test checks them against what numba types
    the loop's calls with); a signature that differs costs the split, never correctness (the callee is
    then compiled here)."""
    from rig_emulator.control.plugin_step import Actuators
    from rig_emulator.control.plugin_step import _control as control
    from rig_emulator.controllers.builtin.kernel import attitude_laws, position_laws
    from rig_emulator.control.supervisor import supervise
    from rig_emulator.estimation.attitude_pipeline import attitude_estimation_step
    from rig_emulator.estimation.load_cell_filter import load_cell_filter_step
    from rig_emulator.guidance.runner import guidance_update
    from rig_emulator.physics.disturbances import extra_mass_effects, shock_torque
    from rig_emulator.physics.integrator import apply_ground
    from rig_emulator.physics.rotation import quat_derivative, quat_normalize, quat_to_rot
    from rig_emulator.simulation import loop

    a = dict(zip(inspect.signature(loop.run_steps.py_func).parameters, args))
    x, sp, ss, ref, cout = a["x"], a["sp"], a["ss"], a["ref"], a["cout"]
    f = 0.0  # a float64 (times, angles, rates)
    pos = x[0:3]  # the loop's pos and vel: x[0:3] or ss.onboard[0:3], both C-contiguous slices
    R = a["R"]
    calls = [  # the rigid body's callees (rk4_step and state_derivative are inlined into the loop)
        (apply_ground, (x, a["pp"], f, f)),
        (quat_normalize, (x[6:10],)),
        (quat_derivative, (f, f, f, f, f, f, f, x[6:10])),
        (shock_torque, (f, a["shocks"])),
        (extra_mass_effects, (a["extra"], R, f)),
        (quat_to_rot, (f, f, f, f, R)),
    ]
    if a["log"].shape[0] > 0:
        calls.append((loop._log_row, (a["log"][0], f, x, a["pp"], sp, ss, ref, cout, a["gstate"], a["v_cmd"], a["us"])))
    calls += [
        (supervise, (f, bool(a["armed"]), sp.simulate, sp.estimated, f, f, f, f, f, cout, ss.awork.ensemble.rejected,
                     ss.awork.combined, ss.health[1], a["up"], a["us"])),
    ]
    if a["pfn"] is not None:  # the controller's turn (none with motor commands from outside)
        cp, pp, pl = a["cp"], a["pp"], a["pl"]
        act = Actuators(cp.arm_length, cp.km_over_kf, cp.f_max, cp.alloc_priority, cp.k_v, cp.v_max)
        # the built-in strategy's stages and the controller's turn first: their compile is the longest single
        # piece, and this process reaches them mid-way through the loop (and the stages again in the kernel)
        calls[:0] = [
            (position_laws, (pl.obs, pl.laws, pl.rig_state, pl.rig_out, False)),
            (attitude_laws, (pl.obs, pl.laws, pl.rig_state, pl.rig_out)),
            (control, (0, f, f, f, pos, pos, f, f, f, f, f, f, f, f, f, ref, a["cstate"], cout, a["v_cmd"],
                       a["scratch"][3], x, sp.simulate, sp.estimated, ss.thrust_est, ss.imu_raw, ss.cell_raw,
                       pp.thrust_efficiency, pp.k_v, pp.f_ceiling, act, pl, a["pfn"])),
        ]
    calls += [
        (guidance_update, (f, pos, a["gp"], a["gstate"], a["reached_t"], ref)),
    ]
    if sp.simulate:  # without sensor models the loop never calls the estimators
        calls += [
            (load_cell_filter_step, (ss.cell_raw, sp.lcp, ss.lcs, ss.thrust_est)),
            (attitude_estimation_step, (0, ss.imu_raw, sp.chain, ss.awork, ss.att_est)),
        ]
    return [(d, tuple(d.typeof_pyval(v) for v in values)) for d, values in calls]


def _jobs_function(dispatcher):
    """The jobs function of ``dispatcher`` (only the step loop has one), else None."""
    from rig_emulator.simulation.loop import run_steps  # here: importing the loop at the top would be a cycle

    return loop_jobs if dispatcher is run_steps else None


class Helper:
    """The helper process and the claims it shares with this process; installed as
    ``_jit._compile_hook`` while the split compile runs (it is called with every dispatcher and
    signature numba is asked to compile, before the compile)."""

    def __init__(self, jobs: list, argv: list | None = None):
        self.jobs = jobs
        self._index = {(id(d), _key(sig)): i for i, (d, sig) in enumerate(jobs)}
        self._thread = threading.get_ident()
        self.waited: dict = {}  # job -> seconds this process waited for the helper (tests, profiling)
        self.compiled_here: list = []  # jobs this process claimed
        self.dir = tempfile.mkdtemp(prefix="hilms-compile-")
        spec = {"cache_dir": _jit.CACHE_DIR,
                "jobs": [(d.py_func.__module__, d.py_func.__qualname__, _key(sig)) for d, sig in jobs]}
        with open(os.path.join(self.dir, "jobs.pickle"), "wb") as fh:
            pickle.dump(spec, fh)
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (_ROOT, env.get("PYTHONPATH")) if p)
        argv = argv or [sys.executable, "-m", "rig_emulator.compile_helper"]
        try:
            with open(os.path.join(self.dir, "helper.log"), "wb") as log:
                self.proc = subprocess.Popen([*argv, self.dir, str(os.getpid())], stdin=subprocess.DEVNULL,
                                             stdout=log, stderr=subprocess.STDOUT, env=env, close_fds=True)
        except BaseException:
            shutil.rmtree(self.dir, ignore_errors=True)
            raise

    def _path(self, i: int, what: str) -> str:
        return os.path.join(self.dir, f"{i}.{what}")

    def __call__(self, dispatcher, sig) -> None:
        if threading.get_ident() != self._thread:
            return
        key = _key(sig)
        i = self._index.get((id(dispatcher), key))
        if i is None or i in self.waited or i in self.compiled_here or key in dispatcher.overloads:
            return
        if claim(self._path(i, "claim")):
            self.compiled_here.append(i)  # the helper has not started it: compile it here
            return
        self.waited[i] = self._wait(i)  # then numba loads the helper's result from the cache (or compiles)

    def _wait(self, i: int) -> float:
        t0 = time.monotonic()
        done = self._path(i, "done")
        while not os.path.exists(done):
            if self.proc.poll() is not None:  # the helper is gone (finished, failed or killed)
                break
            if time.monotonic() - t0 > HANG_GUARD_S:
                self.proc.kill()
                break
            time.sleep(_POLL_S)
        return time.monotonic() - t0

    def close(self) -> None:
        """Stop the helper if it still runs (its remaining jobs were claimed here or are not needed)
        and remove the claims."""
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        shutil.rmtree(self.dir, ignore_errors=True)


def claim(path: str) -> bool:
    try:
        os.close(os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        return True
    except FileExistsError:
        return False


def start(dispatcher, args: tuple, sig) -> Helper | None:
    """A helper for compiling ``dispatcher`` for ``args`` (of types ``sig``), or None when there is
    nothing to share (see the module docstring)."""
    if os.environ.get(ENV_SWITCH) == "0":
        return None
    jobs_function = _jobs_function(dispatcher)
    if jobs_function is None or is_cached(dispatcher, sig) is not False:
        return None  # warm, not cached at all, or numba's cache internals moved: no helper
    jobs = [(d, s) for d, s in jobs_function(args)
            if _key(s) not in d.overloads and is_cached(d, s) is False]
    return Helper(jobs) if jobs and enabled() else None


@contextmanager
def split_compile(dispatcher, args: tuple, sig):
    """Around the compile of ``dispatcher`` for ``args``: a helper process compiles part of its call
    tree meanwhile (when it is the step loop, not cached yet; see the module docstring)."""
    try:
        helper = start(dispatcher, args, sig)
    except Exception:  # noqa: BLE001 - the split only saves time: without it the compile is the same
        helper = None
    if helper is None:
        yield None
        return
    previous, _jit._compile_hook = _jit._compile_hook, helper
    try:
        yield helper
    finally:
        _jit._compile_hook = previous
        helper.close()


def _main(argv: list) -> int:
    """The helper process: ``python -m rig_emulator.compile_helper DIR PARENT_PID``."""
    directory, parent = argv[0], int(argv[1])
    with open(os.path.join(directory, "jobs.pickle"), "rb") as fh:
        spec = pickle.load(fh)
    if _jit.CACHE_DIR != spec["cache_dir"]:
        print(f"compile helper: cache {_jit.CACHE_DIR} is not the caller's {spec['cache_dir']}", flush=True)
        return 2  # another source tree: its cache would not serve the caller
    for i in range(len(spec["jobs"])):
        if os.getppid() != parent:
            return 3  # the caller is gone
        if not claim(os.path.join(directory, f"{i}.claim")):
            continue  # the caller compiles it
        module, qualname, sig = spec["jobs"][i]
        try:
            dispatcher = importlib.import_module(module)
            for part in qualname.split("."):
                dispatcher = getattr(dispatcher, part)
            dispatcher.compile(sig)
        except Exception as exc:  # noqa: BLE001 - the caller compiles it then, and reports any error
            print(f"compile helper: {module}.{qualname}: {type(exc).__name__}: {exc}", flush=True)
        finally:
            claim(os.path.join(directory, f"{i}.done"))
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
