"""Our compiled FLC against scikit-fuzzy 0.5.0's ``ControlSystemSimulation``.

Both sides evaluate the same axis: ``make_axis(radians(1.8), radians(7.0), 0.05)`` (paper
geometry), the 49 rules of Table 1 (``RULE_TABLE``) and the membership geometry of our
term arrays. scikit-fuzzy is configured to reproduce our center-average defuzzifier
(Eq. 14), as the project's performance notes describe:

* input terms: our triangles / shoulders sampled on a universe that contains every vertex
  (so its linear interpolation is exact);
* product AND (``Rule(..., and_func=np.multiply)``) and sum accumulation
  (``Consequent.accumulation_method = np.add``: a rule fired twice counts twice);
* output terms: narrow unit-height rectangles centred on our output centers (half-width
  :data:`OUT_HALF_WIDTH_FRAC` of the spacing, ramps :data:`OUT_RAMP_FRAC` of it); the
  centroid of such sets is the center average of the activations. skfuzzy caps a term's
  (summed) activation at the set's height 1, so every rule's consequent carries the weight
  :data:`ACTIVATION_SCALE` (``u[term] % ACTIVATION_SCALE``): the summed activations stay
  below 1 and the centroid, a ratio, does not change.

The skfuzzy probe evaluates a grid of inputs over the whole universe and reports the
largest difference from our output on it (``max_abs_diff``).

Our side: ``flc_eval_many`` over 100,000 random inputs (the compiled loop; per evaluation
= batch time / N) and ``flc_eval`` called from Python one input at a time (dispatch
overhead included). skfuzzy: ``compute()`` per call as shipped (new inputs each call).
"""

from __future__ import annotations

import math
import time

import numpy as np

from .harness import BenchmarkUnavailable, Metric, ProbeStats, Target, benchmark, paired_ratio_metric, probe

FLC_PROBE = "flc-compute"
SKFUZZY_PROBE = "skfuzzy-compute"

#: The axis both sides evaluate: d1 of e [rad], de [rad/s], u [N m].
AXIS_D1 = (math.radians(1.8), math.radians(7.0), 0.05)
#: Output rectangles: half-width and ramp width as fractions of the output-center spacing.
OUT_HALF_WIDTH_FRAC = 0.01
OUT_RAMP_FRAC = 1e-9
#: Weight of every rule's consequent, keeping summed activations below skfuzzy's cap of 1
#: (the summed strength of all 49 rules is (sum mu_e)(sum mu_de), at most (11/6)^2 ~ 3.4 here).
ACTIVATION_SCALE = 0.0625
#: The universe of an input extends this many ``d1`` beyond the outermost term edge.
INPUT_MARGIN_D1 = 1.0


# ----------------------------------------------------------------------------------------
# Pure helpers (numpy only; unit-tested)
# ----------------------------------------------------------------------------------------


def term_membership(x, terms: np.ndarray, i: int) -> np.ndarray:
    """Membership of ``x`` (array) in input term ``i`` of a ``(7, 4)`` term array (numpy)."""
    x = np.asarray(x, dtype=np.float64)
    c, lw, rw, sh = terms[i]
    left = 1.0 if sh < 0 else 1.0 - (c - x) / lw
    right = 1.0 if sh > 0 else 1.0 - (x - c) / rw
    m = np.where(x < c, left, right)
    return np.clip(m, 0.0, 1.0)


def input_universe(terms: np.ndarray, n: int = 201, margin: float | None = None) -> np.ndarray:
    """Sorted universe covering every term with ``margin`` to spare, containing every vertex."""
    c = terms[:, 0]
    finite = lambda a: a[np.isfinite(a)]  # noqa: E731
    lo_edges = finite(c - terms[:, 1])
    hi_edges = finite(c + terms[:, 2])
    d1 = float(np.min(np.diff(c)))
    margin = INPUT_MARGIN_D1 * d1 if margin is None else margin
    lo = min(lo_edges.min(), c.min()) - margin
    hi = max(hi_edges.max(), c.max()) + margin
    return np.unique(np.concatenate([np.linspace(lo, hi, n), c, lo_edges, hi_edges]))


def output_sets(out_centers: np.ndarray, half_width_frac: float = OUT_HALF_WIDTH_FRAC,
                ramp_frac: float = OUT_RAMP_FRAC, height: float = 1.0):
    """Universe and per-term membership arrays of narrow rectangles around ``out_centers``.

    Returns ``(universe, mfs)`` with ``mfs`` of shape ``(len(out_centers), len(universe))``:
    term ``k`` is ``height`` on ``[y_k - h, y_k + h]``, falls to 0 over ``r`` on each side
    (``h``, ``r`` fractions of the smallest center spacing) and is 0 elsewhere.
    """
    y = np.asarray(out_centers, dtype=np.float64)
    spacing = float(np.min(np.diff(y)))
    h = half_width_frac * spacing
    r = ramp_frac * spacing
    if not (0.0 < r and h + r < 0.5 * spacing):
        raise ValueError("output rectangles must be narrow enough not to overlap")
    pts = np.concatenate([y - h - r, y - h, y + h, y + h + r, [y[0] - spacing, y[-1] + spacing]])
    universe = np.unique(pts)
    mfs = np.zeros((len(y), len(universe)))
    for k, yk in enumerate(y):
        inside = (universe >= yk - h) & (universe <= yk + h)
        mfs[k, inside] = height
    return universe, mfs


def grid_inputs(e_terms: np.ndarray, de_terms: np.ndarray, g: int):
    """``g x g`` grid of (e, de) pairs across both universes (flattened, row-major)."""
    eu = input_universe(e_terms)
    du = input_universe(de_terms)
    e = np.linspace(eu[0], eu[-1], g)
    de = np.linspace(du[0], du[-1], g)
    ee, dd = np.meshgrid(e, de, indexing="ij")
    return ee.ravel(), dd.ravel()


def _axis():
    from rig_emulator.controllers.builtin.fuzzy import RULE_TABLE, make_axis

    return make_axis(*AXIS_D1), RULE_TABLE


# ----------------------------------------------------------------------------------------
# Probes
# ----------------------------------------------------------------------------------------


def build_skfuzzy(axis, rule_table):
    """A ``ControlSystemSimulation`` reproducing our FLC; see the module docstring."""
    try:
        import skfuzzy
        from skfuzzy import control as ctrl
    except ImportError as exc:
        raise BenchmarkUnavailable(
            f"scikit-fuzzy is not importable ({exc}); install the bench extra "
            f"(`pip install -e '.[bench]'`: scikit-fuzzy==0.5.0, networkx)"
        ) from None
    from rig_emulator.controllers.builtin.fuzzy import INPUT_TERMS, OUTPUT_TERMS

    e = ctrl.Antecedent(input_universe(axis.e_terms), "e")
    de = ctrl.Antecedent(input_universe(axis.de_terms), "de")
    for var, terms in ((e, axis.e_terms), (de, axis.de_terms)):
        for i, name in enumerate(INPUT_TERMS):
            var[name] = term_membership(var.universe, terms, i)
    out_u, out_mfs = output_sets(axis.out_centers)
    u = ctrl.Consequent(out_u, "u")
    for k, name in enumerate(OUTPUT_TERMS):
        u[name] = out_mfs[k]
    u.accumulation_method = np.add
    u.defuzzify_method = "centroid"
    rules = [
        ctrl.Rule(e[INPUT_TERMS[i]] & de[INPUT_TERMS[j]], u[OUTPUT_TERMS[int(rule_table[j, i])]] % ACTIVATION_SCALE,
                  and_func=np.multiply)
        for j in range(len(INPUT_TERMS)) for i in range(len(INPUT_TERMS))
    ]
    sim = ctrl.ControlSystemSimulation(ctrl.ControlSystem(rules))
    return sim, skfuzzy.__version__


@probe(SKFUZZY_PROBE, params={"grid": 15}, quick={"grid": 5},
       description="scikit-fuzzy 0.5.0 ControlSystemSimulation.compute() per call, on a grid")
def skfuzzy_compute(grid: int) -> dict:
    """skfuzzy per-call time over a grid x grid of inputs, and its largest difference from ours."""
    axis, rule_table = _axis()
    t0 = time.perf_counter()
    sim, version = build_skfuzzy(axis, rule_table)
    build_s = time.perf_counter() - t0
    e, de = grid_inputs(axis.e_terms, axis.de_terms, grid)
    theirs = np.empty(len(e))
    t0 = time.perf_counter()
    for k in range(len(e)):
        sim.input["e"] = e[k]
        sim.input["de"] = de[k]
        sim.compute()
        theirs[k] = sim.output["u"]
    wall = time.perf_counter() - t0

    from rig_emulator.controllers.builtin.fuzzy import flc_eval_many

    ours = np.empty(len(e))
    flc_eval_many(e, de, axis.e_terms, axis.de_terms, axis.out_centers, rule_table, ours)
    diff = float(np.max(np.abs(ours - theirs)))
    return {"us_per_call": wall / len(e) * 1e6, "calls": len(e), "build_s": build_s,
            "max_abs_diff": diff, "max_abs_diff_rel_d1u": diff / AXIS_D1[2],
            "skfuzzy_version": version}


@probe(FLC_PROBE, params={"n": 100_000, "n_python": 20_000, "batches": 5},
       quick={"n_python": 2_000, "batches": 3},
       description="our FLC: flc_eval_many (compiled loop) and flc_eval called from Python")
def flc_compute(n: int, n_python: int, batches: int) -> dict:
    """Our FLC per evaluation in the compiled loop (batch / n) and per call from Python."""
    t0 = time.perf_counter()
    from rig_emulator.controllers.builtin.fuzzy import flc_eval, flc_eval_many

    axis, rule_table = _axis()
    import_s = time.perf_counter() - t0
    eu = input_universe(axis.e_terms)
    du = input_universe(axis.de_terms)
    rng = np.random.default_rng(0)
    e = rng.uniform(eu[0], eu[-1], n)
    de = rng.uniform(du[0], du[-1], n)
    out = np.empty(n)
    args = (axis.e_terms, axis.de_terms, axis.out_centers, rule_table)
    t0 = time.perf_counter()
    flc_eval_many(e[:1], de[:1], *args, out[:1])
    first_many_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    flc_eval(float(e[0]), float(de[0]), *args)
    first_eval_s = time.perf_counter() - t0
    walls = []
    for _ in range(batches):
        t0 = time.perf_counter()
        flc_eval_many(e, de, *args, out)
        walls.append(time.perf_counter() - t0)
    batch_s = float(np.median(walls))
    ep = [float(x) for x in e[:n_python]]
    dp = [float(x) for x in de[:n_python]]
    t0 = time.perf_counter()
    for k in range(n_python):
        flc_eval(ep[k], dp[k], *args)
    py_wall = time.perf_counter() - t0
    return {"batch_s": batch_s, "n": n, "us_per_eval_compiled": batch_s / n * 1e6,
            "us_per_call_python": py_wall / n_python * 1e6,
            "first_call_s": first_many_s + first_eval_s, "import_s": import_s,
            "checksum": float(np.sum(out))}


@benchmark("flc-vs-skfuzzy", probes=(SKFUZZY_PROBE, FLC_PROBE))
def flc_vs_skfuzzy(stats: dict[str, ProbeStats]) -> list[Metric]:
    """Our compiled FLC vs scikit-fuzzy 0.5.0 on the same rules and geometry."""
    sk, ours = stats[SKFUZZY_PROBE], stats[FLC_PROBE]
    n = int(ours.first("n"))
    target = (Target(">=", 1000.0, "against scikit-fuzzy"),)
    sk_batch = [u * n * 1e-6 for u in sk.values("us_per_call")]
    our_batch = ours.values("batch_s")
    batch_ratios = [a / b for a, b in zip(sk_batch, our_batch)]
    return [
        ours.metric("us_per_eval_compiled", "FLC per evaluation, compiled loop (flc_eval_many / N)", "us"),
        ours.metric("us_per_call_python", "FLC per call from Python (flc_eval dispatch)", "us"),
        sk.metric("us_per_call", "scikit-fuzzy compute() per call", "us"),
        paired_ratio_metric(sk, "us_per_call", ours, "us_per_eval_compiled",
                            "speed-up per evaluation, compiled loop", targets=target),
        paired_ratio_metric(sk, "us_per_call", ours, "us_per_call_python",
                            "speed-up per call from Python", targets=target),
        ours.metric("batch_s", f"FLC batch of {n:,} inputs (flc_eval_many)", "s"),
        Metric(f"scikit-fuzzy {n:,} calls (per call x N)", float(np.median(sk_batch)), "s",
               None, (), min(sk_batch), max(sk_batch)),
        Metric(f"speed-up, batch of {n:,}", float(np.median(batch_ratios)), "x", FLC_PROBE,
               (), min(batch_ratios), max(batch_ratios),
               "equals the compiled per-evaluation speed-up (same timings)"),
        ours.metric("first_call_s", "FLC first calls (compile or cache load)", "s"),
        sk.metric("build_s", "scikit-fuzzy ControlSystemSimulation build", "s"),
        sk.metric("max_abs_diff", "max |u_ours - u_skfuzzy| over the grid", "N m",
                  note=f"grid over both input universes; d1_u = {AXIS_D1[2]} N m"),
    ]
