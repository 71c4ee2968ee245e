"""The one place the compiled hot path is configured.

Every compiled function in the project is decorated with :func:`jit` from here. It is
``numba.njit(cache=True)`` with two guarantees on top:

* **No stale machine code.** numba keys its on-disk cache on the file that defines a
  function only, so editing a callee in another module (or a constant it imports) does
  not invalidate a caller's cached code. We point numba's cache at a directory named by
  a hash of every source file under :data:`COMPILED_ROOTS` (the only places compiled code
  may live; a test checks it): any edit there gives a fresh cache, an unchanged tree
  reuses the old one (a fresh process starts in about a second). Old cache directories
  beyond the newest eight are removed.
* **Determinism.** ``fastmath`` stays off, so results are bit-identical run to run.

``jit(nrt=False)`` compiles a function without numba's reference counting (its runtime,
NRT). With it on, numba increments and decrements an array's reference count (a call
doing an atomic ``lock inc``/``lock dec``) whenever an array, or a namedtuple holding
arrays, is passed to a function that is not inlined, taken out of a namedtuple or sliced,
and its pruning pass leaves many of those in place in loops with branches. In the step
loop that happened many times a step: the two atomics were the hottest instructions of
the whole process (perf), and compiling the loop without them made it 2.4-2.8x faster
with bit-identical results. The step loop's functions that take arrays and are not
``inline="always"`` therefore use ``nrt=False`` (inlined ones take the flag of the
function they are inlined into). Such a function must not allocate (numba refuses to
compile ``np.empty`` or a whole-slice copy without NRT, as the no-allocation-per-step rule
wants) and must not be called from Python with a ``numpy.random.Generator`` (unboxing one
takes a reference that only NRT releases: a leak per call); the loop's entry point
therefore takes the pointers of the generator's bit generator instead
(``rig_emulator/simulation/rng_bits.py``; an NRT wrapper around the loop compiled the whole
loop twice). The flag is always set explicitly, so a function never inherits it from
whichever caller happened to compile it first (numba would otherwise, and its cache does not
tell the two apart).

An ``nrt=False`` function is also compiled without numba's CPython wrapper (it is called
from compiled code; a call from Python runs a twin compiled with one), and no function gets
numba's C-callable wrapper: compiling wrappers nothing calls was a tenth of the cold compile
(docs/explanation/performance.md "Cold compile").

Set ``HILMS_NUMBA_CACHE`` to choose the cache root (default ``~/.cache/hilms-sil``).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import threading
import types
from pathlib import Path

import numba

COMPILED_ROOTS = (
    "rig_emulator/_jit.py",
    "rig_emulator/physics",
    "rig_emulator/control",
    "rig_emulator/controllers/builtin",  # the built-in laws (the rest of controllers/ is plain Python)
    "rig_emulator/guidance",
    "rig_emulator/simulation",
    "rig_emulator/sensors",
    "rig_emulator/estimation",
    "protocol/waypoint_switching.py",  # plain Python compiled by rig_emulator/guidance/waypoint_switching.py
)
_KEEP_CACHES = 8


def compiled_source_files() -> list[Path]:
    """Every Python file whose compiled code the cache may hold."""
    here = Path(__file__).resolve().parent.parent
    files: list[Path] = []
    for root in COMPILED_ROOTS:
        path = here / root
        files.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path])
    return files


def _source_digest() -> str:
    here = Path(__file__).resolve().parent.parent
    h = hashlib.sha256(numba.__version__.encode())
    for path in compiled_source_files():
        h.update(str(path.relative_to(here)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _cache_dir() -> str:
    base = os.environ.get("HILMS_NUMBA_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "hilms-sil")
    return os.path.join(base, "numba-" + _source_digest())


def _prune(current: str) -> None:
    base = Path(current).parent
    try:
        old = sorted(
            (p for p in base.glob("numba-*") if p.is_dir() and str(p) != current),
            key=lambda p: p.stat().st_mtime,
            reverse=True,
        )
        for stale in old[_KEEP_CACHES - 1 :]:
            shutil.rmtree(stale, ignore_errors=True)
    except OSError:
        pass  # pruning is housekeeping; a racing process may have removed a directory first


CACHE_DIR = _cache_dir()
numba.config.CACHE_DIR = CACHE_DIR
_prune(CACHE_DIR)


def _in_large_frame(fn, args, kwargs):
    return fn(*args, **kwargs)


# CPython (3.11+) keeps its frames in 16 KiB chunks of a per-thread stack, mapped when the stack
# grows into one and unmapped as soon as it returns out of it. numba's compiler recurses deeply and
# its depth swings across such boundaries all the time: in a cold compile of the step loop that was
# about 0.55 million page faults (84 % of all, in _PyThreadState_BumpFramePointerSlow; perf) and
# about 5 s of system time (docs/explanation/performance.md, "Cold compile"). A compile therefore starts in a
# frame whose (never touched) stack reservation makes CPython give it a 2 MiB chunk; the compiler's
# frames then live in the rest of that chunk, which stays mapped until the compile returns.
_in_large_frame.__code__ = _in_large_frame.__code__.replace(
    co_stacksize=_in_large_frame.__code__.co_stacksize + (1 << 17))
_compiling = threading.local()
#: called with (dispatcher, signature) before every compile of a dispatcher made by :func:`jit`
#: while a split compile runs (rig_emulator/compile_helper.py); None otherwise
_compile_hook = None


def _outermost(fn, args, kwargs):
    if getattr(_compiling, "active", False):
        return fn(*args, **kwargs)
    _compiling.active = True
    try:
        return _in_large_frame(fn, args, kwargs)
    finally:
        _compiling.active = False


class _LargeFrame:
    """Mixin of every dispatcher made by :func:`jit`: compiles (and cache loads) start in a large
    frame (see :func:`_in_large_frame`); the compiled code is the same."""

    def compile(self, sig):
        hook = _compile_hook
        if hook is not None:
            hook(self, sig)
        return _outermost(super().compile, (sig,), {})

    def _compile_for_args(self, *args, **kws):
        return _outermost(super()._compile_for_args, args, kws)


class _LoopOnly:
    """Mixin of a dispatcher compiled without numba's CPython wrapper (see :func:`jit`)."""

    def __call__(self, *args, **kwargs):
        twin = self.__dict__.get("_python_twin")
        if twin is None:
            twin = self.__dict__["_python_twin"] = _python_twin(self)
        return twin(*args, **kwargs)


def _python_twin(dispatcher):
    """The same function compiled with its CPython wrapper, for calls from Python (tests,
    debugging); its own name ``<name>_py`` gives it its own entries in numba's cache."""
    f = dispatcher.py_func
    g = types.FunctionType(f.__code__, f.__globals__, f.__name__, f.__defaults__, f.__closure__)
    g.__qualname__ = f.__qualname__ + "_py"
    g.__module__ = f.__module__
    g.__doc__ = f.__doc__
    opts = dict(dispatcher.targetoptions)
    opts.pop("no_cpython_wrapper", None)
    opts.pop("nopython", None)
    return numba.njit(cache=dispatcher.__dict__.get("_cache_twin", True), **opts)(g)


def jit(*args, nrt=True, python=None, **kwargs):
    """``numba.njit(cache=True)``; usable bare (``@jit``) or with options (``@jit(inline='always')``,
    ``@jit(nrt=False)``: no reference counting, see the module docstring).

    ``python``: compile numba's CPython wrapper (the code that unboxes every argument when
    Python calls the function). Default: only with ``nrt=True``; an ``nrt=False`` function is
    part of the step loop, called from compiled code only, and compiling a wrapper for its
    namedtuples of arrays that nothing calls cost about a tenth of the cold compile.
    Called from Python anyway (a test), it runs a twin compiled with the wrapper. No function
    gets numba's C-callable (cfunc) wrapper: nothing takes a jitted function's address.
    """
    kwargs.setdefault("cache", True)
    kwargs.setdefault("fastmath", False)
    kwargs.setdefault("no_cfunc_wrapper", True)
    kwargs["_nrt"] = bool(nrt)  # numba's own name for the option
    if python is None:
        python = bool(nrt) or kwargs.get("inline") == "always"
    if not python:
        kwargs["no_cpython_wrapper"] = True

    def wrap(f):
        d = numba.njit(**kwargs)(f)
        d.__class__ = _dispatcher_class(type(d), loop_only=not python)
        if not python:
            d._cache_twin = bool(kwargs["cache"])
        return d

    if len(args) == 1 and callable(args[0]):
        return wrap(args[0])
    if args:
        raise TypeError("jit: signatures are not supported here")
    return wrap


_CLASSES: dict = {}


def _dispatcher_class(cls, loop_only):
    sub = _CLASSES.get((cls, loop_only))
    if sub is None:
        name = ("LoopOnly" if loop_only else "LargeFrame") + cls.__name__
        bases = (_LoopOnly, _LargeFrame, cls) if loop_only else (_LargeFrame, cls)
        sub = _CLASSES[(cls, loop_only)] = type(name, bases, {"__module__": __name__, "__qualname__": name})
        globals()[name] = sub  # importable by name, as pickle finds a class
    return sub
