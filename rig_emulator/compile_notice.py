"""Telling the person at the terminal what is being compiled, and for how long.

The first command after an install (or after an update of the compiled sources) compiles
the step loop with numba; later ones load it from numba's on-disk cache
(:mod:`rig_emulator._jit`) in about a second. Every controller goes through the same loop (the
call through a function pointer: the built-in strategies' kernel, a compiled plug-in, a Python
one), so a plug-in's first run compiles only what is its own: a compiled plug-in
(:class:`~rig_emulator.controllers.CompiledController`) its kernel, once. Each is cached
afterwards.

:func:`compile_notice` wraps the part of a command that compiles: when the cache lacks what
the command is about to compile it prints, on stderr, what is compiled and roughly how long
it takes, and afterwards how long it took. With a warm cache it prints nothing, so a notice
appears once per install for the loop, once per compiled plug-in for its kernel.
"""

from __future__ import annotations

import importlib
import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path

#: cold compile of the step loop on a quiet 2-core machine, a helper process on the second core
#: (rig_emulator/compile_helper.py; measured 21-23 s, docs/explanation/performance.md "Cold compile")
QUIET_COMPILE_S = 25


def _loop_signatures():
    """The argument types of every step loop numba's cache holds ([] when none; None when it cannot tell)."""
    from rig_emulator.simulation.loop import run_steps

    try:
        cache_file = run_steps._cache._cache_file
        if not os.path.exists(cache_file._index_path):
            return []
        return [key[0] for key in cache_file._load_index()]
    except Exception:  # noqa: BLE001 - numba's internals moved
        return None


def step_loop_cached() -> bool:
    """Whether numba's cache already holds the step loop a controller flies (its last argument a
    function pointer: the built-in strategies and plug-ins alike; not the lockstep loop, which has none)."""
    from numba.core import types

    sigs = _loop_signatures()
    if sigs is None:  # any index file in our cache directory
        from rig_emulator import _jit

        return any(Path(_jit.CACHE_DIR).rglob("*.nbi"))
    return any(len(s) and isinstance(s[-1], types.FunctionType) for s in sigs)


def _kernel(spec: str):
    """The numba kernel of the compiled plug-in named ``spec`` (``module:Name``), else None."""
    try:
        module_name, _, attr = spec.partition(":")
        obj = importlib.import_module(module_name)
        for part in attr.split("."):
            obj = getattr(obj, part)
        from rig_emulator.controllers.base import CompiledController

        cls = obj if isinstance(obj, type) else type(obj)
        if not issubclass(cls, CompiledController):
            return None
        kernel = cls.kernel
        return kernel if hasattr(kernel, "py_func") else None
    except Exception:  # noqa: BLE001 - loading the plug-in reports its own errors
        return None


def kernel_cached(kernel) -> bool:
    """Whether numba's cache holds ``kernel`` compiled (for any argument types)."""
    try:
        cache_file = kernel._cache._cache_file
        return os.path.exists(cache_file._index_path) and bool(cache_file._load_index())
    except Exception:  # noqa: BLE001 - not cached at all (cache=False) or moved internals: say nothing
        return True


def what_compiles(plugin: str | None = None, call: str = "compiled") -> str | None:
    """What a run compiles before it starts, in words (None: nothing, the cache holds it all).

    ``plugin``: the controller plug-in flying (``module:Name``), ``call`` its call path."""
    from rig_emulator import _jit

    where = f"cached afterwards in {_jit.CACHE_DIR}"
    kernel = _kernel(plugin) if plugin is not None and call == "compiled" else None
    kernel_cold = kernel is not None and not kernel_cached(kernel)
    if not step_loop_cached():
        extra = f" and the kernel of controller {plugin}" if kernel_cold else ""
        return (f"compiling the step loop{extra} (first run of this install or after an update; about "
                f"{QUIET_COMPILE_S} s on a quiet 2-core machine, longer on a busy one); later runs load it from "
                f"{_jit.CACHE_DIR} in about a second")
    if kernel_cold:
        return (f"compiling the kernel of controller {plugin} (first run of this plug-in; a few seconds, longer "
                f"on a busy machine; {where})")
    return None


@contextmanager
def compile_notice(prog: str = "rig-emulator", stream=None, plugin: str | None = None, call: str = "compiled",
                   cfg=None):
    """Announce a cold compile on ``stream`` (stderr) around the block: the step loop, or with
    ``plugin`` (``module:Name``, flown by ``call``) the plug-in's kernel too;
    ``cfg``: take both from a rig configuration (``controller.plugin``, ``controller.call``).
    Yields whether something was announced."""
    stream = stream if stream is not None else sys.stderr
    if cfg is not None:
        plugin, call = cfg["controller.plugin"] or None, cfg["controller.call"]
    what = what_compiles(plugin, call)
    if what is not None:
        print(f"{prog}: {what}", file=stream, flush=True)
    t0 = time.perf_counter()
    yield what is not None
    if what is not None:
        done = "step loop" if plugin is None else f"controller {plugin}"
        print(f"{prog}: {done} compiled in {time.perf_counter() - t0:.0f} s", file=stream, flush=True)
