"""A deep copy of plain data (dicts, lists, tuples and namedtuples, numpy arrays, scalars)
several times faster than :func:`copy.deepcopy`, for the per-run copies of cached set-up
(configurations, a rig's sensing).

Like ``copy.deepcopy`` it keeps sharing: an object reached twice is copied once and the
copy is reached twice (a rig's parameter tuples share arrays, and writes through one must
show through the other). Arrays are copied with their layout (``ndarray.copy(order="K")``),
so a copy has the numba types of the original. Anything else (dataclasses, random
generators, ...) is handed to ``copy.deepcopy`` with the same memo, except instances of plain
classes and dataclasses (no copy or pickling hooks, no slots), which are copied as
``copy.deepcopy`` copies them (a new instance, its ``__dict__`` copied) without its detour.
"""

from __future__ import annotations

import copy
import functools

import numpy as np

_ATOMIC = (type(None), bool, int, float, complex, str, bytes, np.dtype)


@functools.lru_cache(maxsize=None)
def _plain_object(t: type) -> bool:
    """An instance of ``t`` is copied by ``copy.deepcopy`` as class + ``__dict__`` (a plain class
    or dataclass: no copy hooks, no slots, default pickling)."""
    return (t.__new__ is object.__new__ and t.__reduce_ex__ is object.__reduce_ex__
            and t.__reduce__ is object.__reduce__ and t.__getstate__ is object.__getstate__
            and getattr(t, "__deepcopy__", None) is None and getattr(t, "__setstate__", None) is None
            and "__slots__" not in t.__dict__)


def fast_deepcopy(obj, memo: dict | None = None):
    """A deep copy of ``obj``; see the module docstring."""
    return _copy(obj, {} if memo is None else memo)


def _copy(obj, memo: dict):
    t = type(obj)
    if t in _ATOMIC or isinstance(obj, np.generic):
        return obj
    k = id(obj)
    hit = memo.get(k)
    if hit is not None:
        return hit
    if t is np.ndarray:
        out = obj.copy(order="K")
        if not obj.flags.writeable:
            out.flags.writeable = False
    elif t is dict:
        out = {}
        memo[k] = out
        for key, value in obj.items():
            out[key] = _copy(value, memo)
        return out
    elif t is list:
        out = []
        memo[k] = out
        out.extend(_copy(v, memo) for v in obj)
        return out
    elif t is tuple:
        out = tuple(_copy(v, memo) for v in obj)
    elif isinstance(obj, tuple) and hasattr(t, "_fields"):  # a namedtuple
        out = t(*(_copy(v, memo) for v in obj))
    elif _plain_object(t) and hasattr(obj, "__dict__"):
        # what copy.deepcopy does for it (__reduce_ex__ -> cls.__new__ + __dict__), without the detour
        out = object.__new__(t)
        memo[k] = out
        memo.setdefault(id(memo), []).append(obj)
        out.__dict__.update(_copy(obj.__dict__, memo))
        return out
    else:
        out = copy.deepcopy(obj, memo)
    memo[k] = out
    memo.setdefault(id(memo), []).append(obj)  # keep originals alive while the memo holds their ids
    return out
