"""Telling the person at the terminal that the step loop is being compiled, and for how long.

The first command after an install (or after an update of the compiled sources) compiles
the step loop with numba; later ones load it from numba's on-disk cache
(:mod:`rig_emulator._jit`) in about a second. :func:`compile_notice` wraps the part of a
command that compiles: when the cache holds no step loop yet it prints, on stderr, what is
happening and roughly how long it takes, and afterwards how long it took. With a warm
cache it prints nothing.
"""

from __future__ import annotations

import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path

#: cold compile of the step loop on a quiet 2-core machine, a helper process on the second core
#: (rig_emulator/compile_helper.py; measured 21-23 s, docs/explanation/performance.md "Cold compile")
QUIET_COMPILE_S = 25


def step_loop_cached() -> bool:
    """Whether numba's cache already holds the compiled step loop (of any argument types)."""
    from rig_emulator import _jit
    from rig_emulator.simulation.loop import run_steps

    try:
        return os.path.exists(run_steps._cache._cache_file._index_path)
    except AttributeError:  # numba's internals moved: any index file in our cache directory
        return any(Path(_jit.CACHE_DIR).rglob("*.nbi"))


@contextmanager
def compile_notice(prog: str = "rig-emulator", stream=None):
    """Announce a cold compile of the step loop on ``stream`` (stderr) around the block."""
    stream = stream if stream is not None else sys.stderr
    cold = not step_loop_cached()
    if cold:
        from rig_emulator import _jit

        print(f"{prog}: compiling the step loop (first run of this install or after an update; about "
              f"{QUIET_COMPILE_S} s on a quiet 2-core machine, longer on a busy one); later runs load it "
              f"from {_jit.CACHE_DIR} in about a second", file=stream, flush=True)
    t0 = time.perf_counter()
    yield cold
    if cold:
        print(f"{prog}: step loop compiled in {time.perf_counter() - t0:.0f} s", file=stream, flush=True)
