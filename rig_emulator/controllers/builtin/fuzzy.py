"""The fuzzy logic controller (FLC) of Sec. 3-2: geometry builders and the compiled evaluator.

One FLC axis maps an error ``e = des - actual`` and its rate ``de`` to a control input
``u`` (Eq. 15). The controller is Mamdani with product inference, triangular membership
functions, seven input terms per input (NU NB NS Z PS PB PU), thirteen output terms
(NU NVB NB NM NS NVS Z PVS PS PM PB PVB PU), the 7x7 rule base of Table 1 and the
center-average defuzzifier of Eq. 14::

    u = sum_r(y_r w_r) / sum_r(w_r),   w_r = mu_e,i(e) * mu_de,j(de),   r = (i, j)

summed over all 49 rules (a rule fired twice counts twice: the per-rule sum of Eq. 14).
``sum_r w_r == 0`` (inputs outside every term) gives ``u = 0``.

Units are the caller's, used consistently: SI inside the rig (rad, rad/s, N m for
attitude; m, m/s, N for position). The paper's Table 3 / Table 5 give ``d1`` in degrees
and deg/s; convert them once before building an axis.

Geometry (Fig. 5, not reproduced in the paper's text). Reading, RIG-SPEC Sec. 5:
``d0 = r1 d1``, ``d2 = r2 d1``, ``d3 = r3 d1``, ``dt = r4 d1`` with
``r = (0.6, 0.8, 0.6, 1.2)`` (Sec. 4-2); input term centers at ``0, +-d1, +-(d1+d2),
+-(d1+d2+d3)``; Z has half-width ``d0``; S and B terms have half-width ``dt``; the U terms
are shoulders, 0 at ``center - dt`` rising linearly to 1 at the center and 1 beyond (mirror
for NU). Output term centers are evenly spaced, ``y_k = k d1_u / 2``, ``k = -6..6``.

The geometry is data, not code: an input-term array of shape ``(7, 4)`` holds, per term
``NU..PU``, its center, left half-width, right half-width and a shoulder flag (``-1``: 1
for every input below the center; ``+1``: 1 for every input above it; ``0``: triangle).
The half-width on a shoulder's open side is stored as ``inf`` and never read. Any builder
that returns such an array (see :func:`input_terms`) plugs into the same compiled code.

Rule table (Table 1): ``RULE_TABLE[j, i]`` is the index (0..12, NU..PU) of the output
term of the rule whose error-rate term is ``j`` and whose error term is ``i`` (rows = de,
columns = e, as printed). It is passed into compiled code as an argument.

Consequence worth knowing: Table 1 is Toeplitz (output index ``i + j``) and the output
centers are evenly spaced, so with product inference Eq. 14 separates into
``u = d1_u / 2 (k_e(e) + k_de(de))`` where ``k(x) = sum_i(i mu_i(x)) / sum_i(mu_i(x))`` is
the center average of the term indices ``i = -3..3`` of one input. The surface is a sum of
two one-input curves; with evenly spaced inputs ``k(x) = sat3(x / d1)`` (a saturated PD),
with the paper's ratios it is odd, non-decreasing and reaches +-3 at ``+-(d1 + d2 + dt)``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rig_emulator._jit import jit

INPUT_TERMS = ("NU", "NB", "NS", "Z", "PS", "PB", "PU")
OUTPUT_TERMS = ("NU", "NVB", "NB", "NM", "NS", "NVS", "Z", "PVS", "PS", "PM", "PB", "PVB", "PU")

#: Column layout of an input-term array.
TERM_CENTER = 0
TERM_LEFT_HALF_WIDTH = 1
TERM_RIGHT_HALF_WIDTH = 2
TERM_SHOULDER = 3

#: The paper's membership ratios (r1, r2, r3, r4), Sec. 4-2.
PAPER_RATIOS = (0.6, 0.8, 0.6, 1.2)

# Table 1 as printed (RIG-SPEC Sec. 5): rows = de term NU..PU, columns = e term NU..PU.
_TABLE_1 = (
    "NU  NVB NB  NM  NS  NVS Z",
    "NVB NB  NM  NS  NVS Z   PVS",
    "NB  NM  NS  NVS Z   PVS PS",
    "NM  NS  NVS Z   PVS PS  PM",
    "NS  NVS Z   PVS PS  PM  PB",
    "NVS Z   PVS PS  PM  PB  PVB",
    "Z   PVS PS  PM  PB  PVB PU",
)


def _rule_table_from_names(rows) -> np.ndarray:
    table = np.array(
        [[OUTPUT_TERMS.index(name) for name in row.split()] for row in rows], dtype=np.int64
    )
    table.setflags(write=False)
    return table


#: Table 1 as output-term indices, ``RULE_TABLE[de_term, e_term]`` (read-only, int64).
RULE_TABLE = _rule_table_from_names(_TABLE_1)


class FuzzyAxis(NamedTuple):
    """One FLC axis (Eq. 15): input-term arrays for ``e`` and ``de``, output term centers."""

    e_terms: np.ndarray
    de_terms: np.ndarray
    out_centers: np.ndarray


# ----------------------------------------------------------------------------------------
# Geometry builders (Python side)
# ----------------------------------------------------------------------------------------


def input_terms(centers, left_half_widths, right_half_widths) -> np.ndarray:
    """Build a ``(7, 4)`` input-term array from centers and half-widths (Fig. 3 / Fig. 5).

    The first term (NU) becomes a left shoulder and the last (PU) a right shoulder; their
    open-side half-widths are ignored and stored as ``inf``. Centers must increase and
    neighbouring supports must overlap, so that some term fires for every input (no hole
    where the Eq. 14 guard would silently return 0).
    """
    c = np.asarray(centers, dtype=np.float64)
    lw = np.asarray(left_half_widths, dtype=np.float64)
    rw = np.asarray(right_half_widths, dtype=np.float64)
    n = len(INPUT_TERMS)
    if c.shape != (n,) or lw.shape != (n,) or rw.shape != (n,):
        raise ValueError(f"need {n} centers and half-widths")
    if not np.all(np.isfinite(c)) or np.any(np.diff(c) <= 0.0):
        raise ValueError("term centers must be finite and strictly increasing")
    if not (np.all(lw[1:] > 0.0) and np.all(rw[:-1] > 0.0)):
        raise ValueError("half-widths must be positive")
    right_edge = c[:-1] + rw[:-1]
    left_edge = c[1:] - lw[1:]
    if np.any(right_edge <= left_edge):
        raise ValueError("neighbouring membership functions must overlap (no gaps)")
    terms = np.empty((n, 4), dtype=np.float64)
    terms[:, TERM_CENTER] = c
    terms[:, TERM_LEFT_HALF_WIDTH] = lw
    terms[:, TERM_RIGHT_HALF_WIDTH] = rw
    terms[:, TERM_SHOULDER] = 0.0
    terms[0, TERM_LEFT_HALF_WIDTH] = np.inf
    terms[0, TERM_SHOULDER] = -1.0
    terms[-1, TERM_RIGHT_HALF_WIDTH] = np.inf
    terms[-1, TERM_SHOULDER] = 1.0
    return terms


def paper_input_terms(d1: float, r=PAPER_RATIOS) -> np.ndarray:
    """Input terms of Fig. 3 / Fig. 5 from ``d1`` and ``r = (r1, r2, r3, r4)`` (Sec. 3-2).

    Reading (RIG-SPEC Sec. 5): ``d0 = r1 d1``, ``d2 = r2 d1``, ``d3 = r3 d1``,
    ``dt = r4 d1``; centers ``0, +-d1, +-(d1+d2), +-(d1+d2+d3)``; Z half-width ``d0``;
    S, B half-width ``dt``; U shoulders reach 0 at ``dt`` inside their center.
    """
    r1, r2, r3, r4 = (float(x) for x in r)
    d1 = float(d1)
    if not d1 > 0.0:
        raise ValueError("d1 must be positive")
    d0, d2, d3, dt = r1 * d1, r2 * d1, r3 * d1, r4 * d1
    c1, c2, c3 = d1, d1 + d2, d1 + d2 + d3
    centers = (-c3, -c2, -c1, 0.0, c1, c2, c3)
    half = (dt, dt, dt, d0, dt, dt, dt)
    return input_terms(centers, half, half)


def even_input_terms(d1: float) -> np.ndarray:
    """Evenly spaced input terms: centers ``k d1`` (k = -3..3), triangles reaching 0 at the
    neighbouring centers, shoulders at the ends. The test-oracle geometry of RIG-SPEC Sec. 5:
    with Table 1 it gives ``u = d1_u (sat3(e/d1_e) + sat3(de/d1_de)) / 2`` exactly.
    """
    d1 = float(d1)
    if not d1 > 0.0:
        raise ValueError("d1 must be positive")
    centers = tuple(k * d1 for k in range(-3, 4))
    return input_terms(centers, (d1,) * 7, (d1,) * 7)


def output_centers(d1_u: float) -> np.ndarray:
    """Output term centers ``y_k = k d1_u / 2``, k = -6..6, NU..PU (Fig. 4; RIG-SPEC Reading)."""
    d1_u = float(d1_u)
    if not d1_u > 0.0:
        raise ValueError("d1_u must be positive")
    return np.array([k * d1_u / 2.0 for k in range(-6, 7)], dtype=np.float64)


_GEOMETRIES = {"paper", "even"}


def make_axis(
    d1_e: float, d1_de: float, d1_u: float, r=PAPER_RATIOS, geometry: str = "paper"
) -> FuzzyAxis:
    """A :class:`FuzzyAxis` from the Table 3 / Table 5 parameters ``d1`` of e, de and u.

    ``geometry="paper"`` uses :func:`paper_input_terms` with ratios ``r``; ``"even"`` uses
    :func:`even_input_terms` (``r`` ignored). Units are the caller's.
    """
    if geometry not in _GEOMETRIES:
        raise ValueError(f"geometry must be one of {sorted(_GEOMETRIES)}")
    if geometry == "paper":
        e_terms, de_terms = paper_input_terms(d1_e, r), paper_input_terms(d1_de, r)
    else:
        e_terms, de_terms = even_input_terms(d1_e), even_input_terms(d1_de)
    return FuzzyAxis(e_terms, de_terms, output_centers(d1_u))


# ----------------------------------------------------------------------------------------
# Compiled evaluation (hot path)
# ----------------------------------------------------------------------------------------


@jit(inline="always")
def membership(x, terms, i):
    """Degree of membership of ``x`` in input term ``i`` of ``terms`` (triangle or shoulder)."""
    c = terms[i, 0]
    shoulder = terms[i, 3]
    if x < c:
        if shoulder < 0.0:
            return 1.0
        m = 1.0 - (c - x) / terms[i, 1]
    else:
        if shoulder > 0.0:
            return 1.0
        m = 1.0 - (x - c) / terms[i, 2]
    if m > 0.0:
        return m
    return 0.0


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def flc_eval(e, de, e_terms, de_terms, out_centers, rule_table):
    """FLC output for error ``e`` and error rate ``de`` (Sec. 3-2, Table 1, Eq. 14).

    Product inference ``w = mu_e,i(e) mu_de,j(de)``; center average over the 49 rules
    ``u = sum(y w) / sum(w)`` with ``y = out_centers[rule_table[j, i]]``; 0 if no rule
    fires. Allocation-free; a non-firing error term skips its seven rules.
    """
    n_e = e_terms.shape[0]
    n_de = de_terms.shape[0]
    num = 0.0
    den = 0.0
    for i in range(n_e):
        mu_e = membership(e, e_terms, i)
        if mu_e == 0.0:
            continue
        for j in range(n_de):
            mu_de = membership(de, de_terms, j)
            if mu_de == 0.0:
                continue
            w = mu_e * mu_de
            num += out_centers[rule_table[j, i]] * w
            den += w
    if den == 0.0:
        return 0.0
    return num / den


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def flc_axis(e, de, axis, rule_table):
    """:func:`flc_eval` with the geometry taken from a :class:`FuzzyAxis`."""
    return flc_eval(e, de, axis.e_terms, axis.de_terms, axis.out_centers, rule_table)


@jit
def flc_eval_max(e, de, e_terms, de_terms, out_centers, rule_table, work):
    """Variant of Eq. 14 with max aggregation (Mamdani "max-product", Sec. 3-2).

    Each output term ``k`` gets the height ``W_k = max`` of the strengths of the rules that
    conclude ``k``; then ``u = sum_k(y_k W_k) / sum_k(W_k)`` (center average of heights).
    ``work`` is a float64 scratch array with at least ``len(out_centers)`` entries,
    allocated once by the caller. Reading: the paper names max-product but writes Eq. 14
    over rules; :func:`flc_eval` (per-rule sum) is the default, this is the alternative.
    """
    n_out = out_centers.shape[0]
    for k in range(n_out):
        work[k] = 0.0
    n_e = e_terms.shape[0]
    n_de = de_terms.shape[0]
    for i in range(n_e):
        mu_e = membership(e, e_terms, i)
        if mu_e == 0.0:
            continue
        for j in range(n_de):
            mu_de = membership(de, de_terms, j)
            if mu_de == 0.0:
                continue
            w = mu_e * mu_de
            k = rule_table[j, i]
            if w > work[k]:
                work[k] = w
    num = 0.0
    den = 0.0
    for k in range(n_out):
        num += out_centers[k] * work[k]
        den += work[k]
    if den == 0.0:
        return 0.0
    return num / den


@jit
def flc_eval_many(e, de, e_terms, de_terms, out_centers, rule_table, out):
    """:func:`flc_eval` element-wise over 1-D arrays ``e``, ``de`` (same length) into ``out``."""
    for n in range(e.shape[0]):
        out[n] = flc_eval(e[n], de[n], e_terms, de_terms, out_centers, rule_table)
