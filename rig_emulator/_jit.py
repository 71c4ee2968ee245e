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
therefore keeps NRT and hands over to an ``nrt=False`` body. The flag is always set
explicitly, so a function never inherits it from whichever caller happened to compile it
first (numba would otherwise, and its cache does not tell the two apart).

Set ``HILMS_NUMBA_CACHE`` to choose the cache root (default ``~/.cache/hilms-sil``).
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

import numba

COMPILED_ROOTS = (
    "rig_emulator/_jit.py",
    "rig_emulator/physics",
    "rig_emulator/control",
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


def jit(*args, nrt=True, **kwargs):
    """``numba.njit(cache=True)``; usable bare (``@jit``) or with options (``@jit(inline='always')``,
    ``@jit(nrt=False)``: no reference counting, see the module docstring)."""
    kwargs.setdefault("cache", True)
    kwargs.setdefault("fastmath", False)
    kwargs["_nrt"] = bool(nrt)  # numba's own name for the option
    if len(args) == 1 and callable(args[0]):
        return numba.njit(**kwargs)(args[0])
    return numba.njit(*args, **kwargs)
