"""The stability analysis (Eq. 16-32) as a self-contained Markdown section, our numbers next to Eq. 42/43."""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.stability import paper_values

_AXIS_LABEL = {"phi": "phi (u2)", "theta": "theta (u3)", "psi": "psi (u4)"}


def _g(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def _matrix(M: np.ndarray) -> list[str]:
    rows = ["| " + " | ".join(f"{v:.4g}" for v in row) + " |" for row in np.asarray(M)]
    head = "| " + " | ".join(f"e{i + 1}" for i in range(M.shape[1])) + " |"
    return [head, "|" + "---|" * M.shape[1], *rows]


def _planes(r) -> list[str]:
    out = [
        "### Fitted planes (Eq. 16; compare Eq. 42)",
        "",
        "Least-squares planes `u_est = kp e + kd de` through the origin, fitted to the FLC surface the rig flies "
        f"(geometry `{r.flc_geometry}`, r = {list(r.flc_r)}) over an {r.planes[0].grid_points} x "
        f"{r.planes[0].grid_points} grid of |e| <= e_max, |de| <= de_max (fit.scale = {_g(r.settings.fit_scale)} "
        "times the inputs' saturation edges). SI units: kp in N m/rad, kd in N m s/rad.",
        "",
        "| axis | kp ours | kd ours | kp Eq. 42 | kd Eq. 42 | e_max (deg) | de_max (deg/s) | max abs(u - u_est) (N m) "
        "| share of grid with d < 0 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p, (kp_p, kd_p) in zip(r.planes, paper_values.KAPPA_GAINS):
        out.append(
            f"| {_AXIS_LABEL[p.axis]} | {_g(p.kp)} | {_g(p.kd)} | {kp_p} | {kd_p} | {_g(math.degrees(p.e_max))} "
            f"| {_g(math.degrees(p.de_max))} | {_g(p.residual_max)} | {p.d_negative_fraction:.0%} |"
        )
    dev = max(abs(p.kp / p.kd - p.de_max / p.e_max) / (p.de_max / p.e_max) for p in r.planes)
    ratios = "; ".join(
        f"{p.axis}: kp/kd = {_g(p.kp / p.kd, 3)} s, de_max/e_max = {_g(p.de_max / p.e_max, 3)} s, "
        f"Eq. 42: {_g(kp / kd, 3)} s"
        for p, (kp, kd) in zip(r.planes, paper_values.KAPPA_GAINS)
    )
    out += [
        "",
        f"{ratios}. Table 1 is Toeplitz and both inputs of an axis share the ratios r, so the surface is a sum of "
        "one curve in e/d1_e and the same curve in de/d1_de; over a rectangle whose sides are in the ratio of the "
        "d1 values (as here) the fit therefore gives kp/kd = de_max/e_max = d1_de/d1_e "
        f"(largest relative deviation here: {dev:.1e}). Eq. 42's kp/kd is not Table 3's d1_de/d1_e ("
        + ", ".join(_g(dd / de, 3) for de, dd in paper_values.TABLE3_D1)
        + " s): the paper states neither the fit range nor the units of kappa.",
    ]
    neg = [p for p in r.planes if p.d_negative_fraction > 0.0]
    if neg:
        out += [
            "",
            "d = (u - u_est) sgn(e) of Eq. 17 is negative on part of the grid ("
            + ", ".join(f"{p.axis} {p.d_negative_fraction:.0%}, min {_g(p.d_min, 3)} N m" for p in neg)
            + "), so the paper's assumption that d has the sign of e (S >= 0 in Eq. 26, 30) does not hold for this "
            "surface; the bound below treats the whole residual as the bounded error d*.",
        ]
    else:
        out += ["", "d = (u - u_est) sgn(e) of Eq. 17 is >= 0 on the whole grid, as Eq. 26 and 30 assume; the bound "
                "below still treats the whole residual as the bounded error d*."]
    return out


def _form_line(f) -> str:
    return f"**{f.verdict}**"


def _p_section(r) -> list[str]:
    d = r.derived
    out = ["### P from the LMI of Eq. 32 (compare Eq. 43)", ""]
    if d.sdp.P is None or not d.feasible:
        out += ["No P: the derived LMI is " + _form_line(d) + ".", "", "```", d.explanation(), "```", ""]
        return out
    rel = float(np.max(np.abs(d.sdp.P - d.scipy.P0)) / np.max(np.abs(d.scipy.P0)))
    lam = d.sdp.p_eigenvalues
    paper = np.array(paper_values.P_EIGENVALUES)
    out += [
        f"Solved with cvxpy/{d.sdp.solver} (status {d.sdp.status}) as: minimise trace(P) subject to "
        f"P >= {_g(r.settings.lmi_p_floor)} I and A^T P + P A <= -{_g(r.settings.lmi_margin)} I, A = N - h kappa. "
        f"Max eigenvalue of A^T P + P A: {d.sdp.lmi_max_eigenvalue:.6g} (< 0, checked with numpy). "
        f"scipy's solve_continuous_lyapunov gives the same P (max relative difference {rel:.1e}), "
        "as it must: the trace-minimal P is the Lyapunov solution.",
        "",
        *_matrix(d.sdp.P),
        "",
        "The LMI is homogeneous in P (any positive multiple solves it), so only the eigenvalues' ratios can be "
        "compared; the paper does not state its normalisation.",
        "",
        "| i | eig(P) ours | ours / max | Eq. 43 | Eq. 43 / max |",
        "|---|---|---|---|---|",
    ]
    for i in range(6):
        out.append(f"| {i + 1} | {_g(lam[i])} | {_g(lam[i] / lam[-1], 3)} | {paper[i]} | {_g(paper[i] / paper[-1], 3)} |")
    pp = r.paper_p
    out += [
        "",
        f"Eq. 43's P is {'symmetric' if pp.symmetric else 'printed non-symmetric'}; its listed eigenvalues are those of "
        f"the printed matrix ({', '.join(_g(x, 3) for x in pp.eig_printed)}). V = e^T P e / 2 only sees the symmetric "
        f"part, whose eigenvalues are {', '.join(_g(x, 3) for x in pp.eig_symmetric_part)}: "
        + ("positive definite" if pp.positive_definite else "**not positive definite**")
        + ". With the paper's kappa and this rig's inertia, that symmetric part gives "
        f"max eig(F^T P + P F) = {_g(pp.lmi_max_eigenvalue['printed'])} for Eq. 32 as printed (second line, H > 0, "
        f"{'holds' if pp.lmi_max_eigenvalue['printed'] < 0 else 'fails'}) and max eig(A^T P + P A) = "
        f"{_g(pp.lmi_max_eigenvalue['derived'])} for the derived form "
        f"({'holds' if pp.lmi_max_eigenvalue['derived'] < 0 else 'fails'}; both need < 0). "
        + _paper_p_verdict(pp),
    ]
    return out


def _paper_p_verdict(pp) -> str:
    if pp.satisfies("derived") or pp.satisfies("printed"):
        forms = [f for f in ("derived", "printed") if pp.satisfies(f)]
        return f"The published P satisfies the {' and the '.join(forms)} form."
    if not pp.positive_definite and pp.lmi_max_eigenvalue["printed"] < 0:
        return ("The published P meets H > 0 of Eq. 32 as printed but not P > 0, consistent with the printed LMI "
                "having no solution (next section).")
    return "The published P satisfies neither form."


def _printed_section(r) -> list[str]:
    return [
        "### Eq. 32 as printed",
        "",
        "Eq. 19 with Eq. 23 gives e' = (N - h kappa) e + ..., so V' < 0 needs P h kappa + kappa^T h^T P - P N - N^T P > 0. "
        "Eq. 25, 26 and 32 print + P N + N^T P instead, i.e. F^T P + P F < 0 with F = -(h kappa + N). Per axis F has "
        "the characteristic polynomial s^2 + (kd/I) s - kp/I, whose constant term is negative for every kp > 0.",
        "",
        f"With our gains: {_form_line(r.printed)}. With the paper's gains (Eq. 42): {_form_line(r.paper_printed)}.",
        "",
        "```",
        r.printed.explanation(),
        "```",
        "",
        f"With the paper's gains, the derived form is {_form_line(r.paper_derived)}"
        + (
            f" (eig(P) = {', '.join(_g(x, 3) for x in r.paper_derived.sdp.p_eigenvalues)} with the same normalisation)."
            if r.paper_derived.feasible else "."
        ),
    ]


def _bound_section(r) -> list[str]:
    b = r.bound
    if b is None:
        return ["### Ultimate bound (Eq. 31)", "", "Not computed: the derived LMI has no verified P."]
    wd = r.settings.desired_rate_max_deg_s
    return [
        "### Ultimate bound R2 (Eq. 27-31)",
        "",
        "|e| is the norm of the 6-vector of angle (rad) and rate (rad/s) errors, as in the paper.",
        "",
        f"* g_max (Eq. 27) from the gyroscopic terms of Eq. A10 with |desired rates| <= {list(wd)} deg/s and "
        f"|rate errors| <= de_max: |g_max| = {_g(b.g_max_norm)} rad/s^2.",
        f"* |d*| = norm of the per-axis max abs(u - u_est): {_g(b.d_star_norm)} N m.",
        f"* sigma_max(P) = {_g(b.sigma_max_P)}, sigma_max(P h) = {_g(b.sigma_max_Ph)}, "
        f"sigma_min(H) = {_g(b.sigma_min_H)} (H = -(A^T P + P A)).",
        f"* **R2 (Eq. 31 as printed) = {_g(b.r2)}**; keeping the 1/2 of V = e^T P e / 2 (Eq. 21-22), V1 of Eq. 29 "
        f"changes sign at 2 R2 = {_g(b.r2_derived)}.",
        f"* Level set of V containing that ball: |e| <= {_g(b.ultimate_bound)} (2 R2 sqrt(cond P)).",
        f"* The plane-plus-residual model holds only inside the fit rectangle, whose smallest half-width is "
        f"{_g(b.region_radius)}: R2 is {'inside' if b.r2 <= b.region_radius else 'outside'} it and the "
        f"level-set bound is {'inside' if b.inside_region else 'outside'} it"
        + ("." if b.inside_region else
           ", so the argument of Eq. 28-31 does not certify ultimate boundedness for this surface; it only holds "
           "where the fit holds."),
        "",
        "The paper gives no number for R2.",
    ]


def markdown(r) -> str:
    """The report section for a :class:`~gcs_tools.stability.result.StabilityResult`."""
    ixx, iyy, izz = r.inertia
    verdict = (
        "is **feasible**: a positive-definite P exists and the FLC attitude loop, linearised by the fitted planes, "
        "is stable" if r.feasible else f"is **{r.derived.verdict}**"
    )
    lines = [
        "## FLC stability (Eq. 16-32)",
        "",
        f"Airframe `{r.airframe}` (Ixx, Iyy, Izz = {_g(ixx)}, {_g(iyy)}, {_g(izz)} kg m^2). Reproduce with "
        "`rig-gcs stability` (JSON: `--json`).",
        "",
        f"**Feasibility.** The LMI of Eq. 32 in the form that follows from Eq. 19-25 (A^T P + P A < 0, P > 0, "
        f"A = N - h kappa) {verdict} for the configured gains. The LMI exactly as printed in Eq. 32 "
        f"(P(h kappa + N) + (h kappa + N)^T P > 0) is **{r.printed.verdict}** for the configured gains and "
        f"**{r.paper_printed.verdict}** for the paper's Eq. 42 gains: its + P N + N^T P term has the opposite sign "
        "to the error dynamics of Eq. 19 and 23 (details below).",
        "",
        *_planes(r),
        "",
        *_p_section(r),
        "",
        *_printed_section(r),
        "",
        *_bound_section(r),
        "",
    ]
    return "\n".join(lines)
