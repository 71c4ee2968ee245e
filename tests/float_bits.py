"""Comparing the scalar (``math``) and array (numpy) forms of a computation, to the last bit where
this host's numpy calls the C library's functions and to a few units in the last place where it
does not.

On x86-64 hosts with AVX-512 numpy runs its own SIMD kernels for ``arctan2``, ``arcsin``,
``arccos``, ``arctan``, ``hypot``, ``exp``, ``log`` and ``tan``, even on one float; they differ
from libm (``math``) in the last bit for up to 7 % of arguments (measured on an AMD
EPYC with AVX512_ICL, numpy 2.4.6, 20,000 arguments each). ``sqrt``, ``sin`` and ``cos`` matched
there. Without AVX-512 numpy calls libm and the two agree to the bit.
"""

import math
import struct

import numpy as np

from protocol.geodesy import WGS84_A_M


def _numpy_is_libm() -> bool:
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=4096) * 3.0, rng.normal(size=4096)
    c = np.clip(x / 3.0, -1.0, 1.0)
    return (np.array_equal(np.arctan2(x, y), [math.atan2(a, b) for a, b in zip(x.tolist(), y.tolist())])
            and np.array_equal(np.arcsin(c), [math.asin(a) for a in c.tolist()])
            and np.array_equal(np.hypot(x, y), [math.hypot(a, b) for a, b in zip(x.tolist(), y.tolist())]))


NUMPY_IS_LIBM = _numpy_is_libm()
"""Whether numpy's atan2, asin and hypot give libm's numbers to the bit on this host."""


def bits(values) -> bytes:
    """The IEEE 754 bytes of the values, NaN payloads and signed zeros included."""
    return b"".join(struct.pack("<d", float(v)) for v in values)


def within_ulps(got, want, ulps: int = 4, scale: float | None = None) -> bool:
    """Each ``got`` within ``ulps`` units in the last place of its ``want`` (of ``scale`` where
    given: for a result computed as a difference of numbers of that size); NaN matches NaN."""
    for g, w in zip(got, want, strict=True):
        g, w = float(g), float(w)
        if math.isnan(g) or math.isnan(w):
            if not (math.isnan(g) and math.isnan(w)):
                return False
            continue
        if abs(g - w) > ulps * math.ulp(w if scale is None else scale):
            return False
    return True


def same_or_within_ulps(got, want, ulps: int = 4, scale: float | None = None) -> bool:
    """Bit for bit where :data:`NUMPY_IS_LIBM`, else :func:`within_ulps`."""
    if NUMPY_IS_LIBM:
        return bits(got) == bits(want)
    return within_ulps(got, want, ulps, scale)


def same_geodetic(got, want) -> bool:
    """(lat_deg, lon_deg, alt_m) triples by :func:`same_or_within_ulps`: the angles in ulps of
    themselves, the height in ulps of the Earth's radius (the size of the terms it is the
    difference of)."""
    return same_or_within_ulps(got[:2], want[:2]) and same_or_within_ulps(got[2:], want[2:], scale=WGS84_A_M)
