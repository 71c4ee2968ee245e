"""The compiled step loop's entry point for a rig's arguments, found without numba's typing.

Calling a numba dispatcher types every argument (``typeof``) to pick the compiled
overload. The step loop takes about thirty arguments, several of them namedtuples of
arrays, and typing them costs milliseconds: more than a short headless run simulates in
(a 5 s run of the full-fidelity rig takes about 6 ms). A rig therefore calls the overload's
entry point directly (see ``Simulation._advance``), and this module finds that entry point
from a **structural key** of the arguments that is cheap to compute: per array its dtype,
number of dimensions, layout, writeability and alignment (what numba's array type holds),
per Python scalar its type, per tuple or namedtuple its class and its items' keys. Two
argument lists with equal keys have equal numba types, so the key maps to one overload;
an argument of any other kind gives no key and the lookup falls back to numba's own
typing (a test compares the two over every preset and strategy).
"""

from __future__ import annotations

import operator

import numpy as np
from numba.core.ccallback import CFunc
from numba.core.types.function_type import WrapperAddressProtocol

_SCALARS = (bool, float, np.random.Generator, type(None))
_INT64 = (-(2**63), 2**63)
_ENTRIES: dict = {}  # (dispatcher id, key) -> entry point


def arg_key(a):
    """The structural key of one argument (None when it has none)."""
    t = type(a)
    if t is np.ndarray:
        f = a.flags
        layout = "C" if f.c_contiguous else ("F" if f.f_contiguous else "A")
        return (a.dtype, a.ndim, layout, f.writeable, f.aligned)
    if t in _SCALARS:
        return t
    if isinstance(a, np.random.BitGenerator):  # the loop's rng travels as its bit generator (rng_bits.py)
        return t
    if t is int:
        return t if _INT64[0] <= a < _INT64[1] else None
    sig = _function_signature(a)
    if sig is not None:  # a controller plug-in's function pointer: its numba type is its signature
        return ("fn", sig)
    if isinstance(a, tuple):
        items = tuple(arg_key(v) for v in a)
        return None if None in items else (t, items)
    return None


def _function_signature(a):
    """The signature of a numba first-class function value (cfunc or WrapperAddressProtocol), else None."""
    if isinstance(a, CFunc):
        return str(a._sig)
    if isinstance(a, WrapperAddressProtocol):
        return str(a.signature())
    return None


def entry_point(dispatcher, args: tuple):
    """The compiled entry point of ``dispatcher`` for ``args`` (compiled, or loaded from the
    on-disk cache, the first time a signature is seen)."""
    key = arg_key(args)
    if key is not None:
        hit = _ENTRIES.get((id(dispatcher), key))
        if hit is not None:
            return hit
    sig = signature(dispatcher, args)
    if sig not in dispatcher.overloads:
        from rig_emulator.compile_helper import split_compile

        with split_compile(dispatcher, args, sig):  # cold: a second process compiles part of the loop
            dispatcher.compile(sig)
            for a in args:  # a function pointer compiled on first use (the built-in strategy's kernel):
                if hasattr(type(a), "compile_now"):  # now, while the helper may hold it compiled
                    a.compile_now()
    entry = dispatcher.overloads[sig].entry_point
    if key is not None:
        _ENTRIES[(id(dispatcher), key)] = entry
    return entry


def signature(dispatcher, args: tuple) -> tuple:
    """numba's own types of ``args`` (what the key stands for)."""
    return tuple(dispatcher.typeof_pyval(a) for a in args)


class BoundEntry:
    """The entry point of one dispatcher for the argument objects a caller last passed: looked
    up (:func:`entry_point`) again only when one of them is replaced (a parameter change, a new
    mission, ...). The objects are compared by identity and held, so that their ids cannot be
    reused; leave scalars out of ``objs``."""

    __slots__ = ("dispatcher", "_objs", "_entry")

    def __init__(self, dispatcher):
        self.dispatcher = dispatcher
        self.forget()

    def forget(self) -> None:
        """Look the entry point up again on the next call."""
        self._objs = None
        self._entry = None

    def __call__(self, args: tuple, objs: tuple):
        """The entry point for ``args``, whose non-scalar objects are ``objs``."""
        prev = self._objs
        if prev is None or not all(map(operator.is_, objs, prev)):
            self._entry = entry_point(self.dispatcher, args)  # compiles or loads the cache the first time
            self._objs = objs
        return self._entry
