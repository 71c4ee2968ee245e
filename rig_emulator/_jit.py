"""The one place the compiled hot path is configured.

Every compiled function in the project is decorated with :func:`jit` from here. It is
``numba.njit(cache=True)`` with two guarantees on top:

* **No stale machine code.** numba keys its on-disk cache on the file that defines a
  function only, so editing a callee in another module (or a constant it imports) does
  not invalidate a caller's cached code. We point numba's cache at a directory named by
  a hash of every source file of ``rig_emulator`` and ``protocol``: any edit gives a
  fresh cache, an unchanged tree reuses the old one (a fresh process starts in < 1 s).
* **Determinism.** ``fastmath`` stays off, so results are bit-identical run to run.

Set ``HILMS_NUMBA_CACHE`` to choose the cache root (default ``~/.cache/hilms-sil``).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba

_PACKAGE_ROOTS = ("rig_emulator", "protocol")


def _source_digest() -> str:
    here = Path(__file__).resolve().parent.parent
    h = hashlib.sha256(numba.__version__.encode())
    for root in _PACKAGE_ROOTS:
        for path in sorted((here / root).rglob("*.py")):
            h.update(str(path.relative_to(here)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _cache_dir() -> str:
    base = os.environ.get("HILMS_NUMBA_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "hilms-sil"
    )
    return os.path.join(base, "numba-" + _source_digest())


CACHE_DIR = _cache_dir()
numba.config.CACHE_DIR = CACHE_DIR


def jit(*args, **kwargs):
    """``numba.njit(cache=True)``; usable bare (``@jit``) or with options (``@jit(inline='always')``)."""
    kwargs.setdefault("cache", True)
    kwargs.setdefault("fastmath", False)
    if len(args) == 1 and callable(args[0]) and not kwargs.keys() - {"cache", "fastmath"}:
        return numba.njit(cache=kwargs["cache"], fastmath=kwargs["fastmath"])(args[0])
    return numba.njit(*args, **kwargs)
