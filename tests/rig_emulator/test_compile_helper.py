"""The cold compile's helper process (rig_emulator/compile_helper.py): its signatures are the
ones numba types the step loop's calls with, this process picks its results up from the cache, and it
falls back to compiling here when the helper fails, hangs or is not wanted."""

import os
import subprocess
import sys

import numba
import pytest

from rig_emulator import _jit, compile_helper
from rig_emulator.config.loader import load_config
from rig_emulator.simulation.entry_points import signature
from rig_emulator.simulation.loop import run_steps
from rig_emulator.simulation.run import Simulation


def _loop_args(**overrides):
    """The step loop's arguments of a rig (as Simulation._advance passes them)."""
    sim = Simulation(load_config(scenario="hover", overrides={"sim.duration": 0.01, "sensors.calibration": "none",
                                                              **overrides}))
    seen = []
    real = sim._loop

    def record(args, objs):
        seen.append(args)
        return real(args, objs)

    sim._loop = record
    sim.advance(1)
    return seen[0]


class _AllSeen(BaseException):
    """Ends the typing of the loop once every job's call was seen (nothing in numba catches it)."""


@pytest.mark.parametrize("overrides", [{}, {"sensors.simulate": False}], ids=["sensors", "no-sensors"])
def test_jobs_are_the_signatures_the_loop_calls(overrides):
    try:
        args = _loop_args(**overrides)
    except Exception as exc:  # noqa: BLE001 - a config key this tree does not have
        pytest.skip(f"config: {exc}")
    jobs = compile_helper.loop_jobs(args)
    assert len(jobs) >= 4
    wanted = {(id(d), compile_helper._key(s)) for d, s in jobs}
    seen = set()

    def hook(dispatcher, sig):
        seen.add((id(dispatcher), compile_helper._key(sig)))
        if wanted <= seen:
            raise _AllSeen

    def afresh(dispatcher, sig):
        """``dispatcher`` compiled afresh (not from the cache), its callees from the cache: the hook sees
        every call numba types in it."""
        opts = {k: v for k, v in dispatcher.targetoptions.items() if k not in ("cache", "nopython")}
        numba.njit(cache=False, **opts)(dispatcher.py_func).compile(sig)

    previous, _jit._compile_hook = _jit._compile_hook, hook
    try:
        afresh(run_steps, signature(run_steps, args))
        # a job the loop reaches through another job (the built-in strategy's laws, through the controller's
        # turn): typed when that job is compiled
        for d, sig in [(d, sig) for d, sig in jobs if (id(d), compile_helper._key(sig)) in seen]:
            afresh(d, sig)
    except _AllSeen:
        pass
    finally:
        _jit._compile_hook = previous
    missing = [f"{d.py_func.__qualname__}{s}" for d, s in jobs if (id(d), compile_helper._key(s)) not in seen]
    assert not missing


def test_no_helper_for_a_cached_loop_or_when_switched_off(monkeypatch):
    args = _loop_args()  # the loop is in the cache now
    sig = signature(run_steps, args)
    assert compile_helper.is_cached(run_steps, sig) is True
    assert compile_helper.start(run_steps, args, sig) is None
    monkeypatch.setenv(compile_helper.ENV_SWITCH, "0")
    assert not compile_helper.enabled()
    monkeypatch.setenv(compile_helper.ENV_SWITCH, "1")
    assert compile_helper.enabled()
    monkeypatch.delenv(compile_helper.ENV_SWITCH)
    assert 0.0 <= compile_helper.idle_cores() <= (os.cpu_count() or 1)  # automatic: a helper when a core is idle
    uncached = _jit.jit(cache=False)(lambda v: v + 1.0)
    assert compile_helper.is_cached(uncached, (numba.float64,)) is None  # cannot tell: no helper
    assert compile_helper.start(uncached, (1.0,), (numba.float64,)) is None


# run in a fresh process with an empty cache: a helper compiles euler_from_quat and euler_rates_from_body_rates,
# this process then "types a caller" that reaches both (the hook, then numba's compile)
_SCRIPT = """
import sys
from numba import float64
from rig_emulator import _jit, compile_helper
from rig_emulator.physics.rotation import euler_from_quat, euler_rates_from_body_rates
mode = sys.argv[1]
if mode == "hang":
    compile_helper.HANG_GUARD_S = 0.5
argv = {"ok": None,
        "dies": [sys.executable, "-c", "import sys; sys.exit(1)"],
        "hang": [sys.executable, "-c", "import os, sys, time; [os.close(os.open(os.path.join(sys.argv[1], f'{i}.claim'), "
                 "os.O_CREAT | os.O_WRONLY)) for i in (0, 1)]; time.sleep(600)"]}[mode]
q = (float64,) * 4
r = (float64,) * 5
jobs = [(euler_rates_from_body_rates, r), (euler_from_quat, q)]  # the helper takes them in this order
helper = compile_helper.Helper(jobs, argv=argv)
if mode == "ok":
    helper.proc.wait()  # let it finish both (a caller would otherwise claim what it has not started)
if mode == "hang":  # let it claim both first
    import os, time
    while not all(os.path.exists(os.path.join(helper.dir, f"{i}.claim")) for i in (0, 1)):
        time.sleep(0.01)
_jit._compile_hook = helper
try:
    euler_from_quat.compile(q)
    euler_rates_from_body_rates.compile(r)
finally:
    _jit._compile_hook = None
    helper.close()
import os
assert not os.path.exists(helper.dir)
assert helper.proc.poll() is not None
hits = sum(sum(d.stats.cache_hits.values()) for d, _ in jobs)
print(mode, hits, sorted(helper.waited), helper.compiled_here)
print(euler_from_quat(1.0, 0.0, 0.0, 0.0), euler_rates_from_body_rates(0.1, 0.2, 0.3, 0.4, 0.5))
"""


def _run(mode, tmp_path):
    p = subprocess.run([sys.executable, "-c", _SCRIPT, mode], env={**os.environ, "HILMS_NUMBA_CACHE": str(tmp_path)},
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return p.stdout.split("\n")


def test_the_callees_come_from_the_helper(tmp_path):
    out = _run("ok", tmp_path)
    assert out[0] == "ok 2 [0, 1] []"  # both loaded from the helper's cache entries, none compiled here


def test_a_dead_helper_means_compiling_here(tmp_path):
    out = _run("dies", tmp_path)
    # the helper died before claiming anything: this process claims and compiles both itself
    assert out[0] == "dies 0 [] [1, 0]"
    assert out[1] == _run("ok", tmp_path / "ok")[1]  # the same results


def test_a_hanging_helper_is_given_up(tmp_path):
    out = _run("hang", tmp_path)
    # the helper claimed both and never finished: the wait gives up, kills it and compiles here
    assert out[0].startswith("hang 0 [0, 1] []")
