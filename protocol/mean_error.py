"""The paper's mean error, Eq. 45: ``ME = sum |x - x_des| / n``, for phi, theta, psi, X, Y, Z.

Shared by the rig (headless runs) and the ground tools (tlogs), so both give the same
numbers from the same samples. Angles are reported in degrees and positions in metres,
the layout of Table 6.
"""

from __future__ import annotations

import math

import numpy as np

COLUMNS = ("phi_deg", "theta_deg", "psi_deg", "x_m", "y_m", "z_m")

PAPER_TABLE_6 = {
    "flc": dict(zip(COLUMNS, (0.7460, 0.5472, 0.8652, 0.0724, 0.0607, 0.2279))),
    "smc-flc": dict(zip(COLUMNS, (0.5096, 0.4926, 0.8197, 0.0659, 0.0550, 0.2263))),
}


def mean_error(actual, desired, angle: bool = False) -> float:
    """Eq. 45 over the samples where both are finite; NaN when there are none.

    ``angle=True`` wraps the difference into (-pi, pi] first.
    """
    a = np.asarray(actual, dtype=float)
    d = np.asarray(desired, dtype=float)
    ok = np.isfinite(a) & np.isfinite(d)
    if not ok.any():
        return math.nan
    diff = a[ok] - d[ok]
    if angle:
        diff = (diff + math.pi) % (2.0 * math.pi) - math.pi
    return float(np.abs(diff).sum() / diff.size)


def mean_errors(t, euler, euler_des, pos, pos_des, window: tuple[float, float] | None = None) -> dict[str, float]:
    """Table 6's six mean errors from time series (angles in rad in, degrees out).

    ``window = (t_start, t_end)`` restricts the samples (both ends included).
    """
    t = np.asarray(t, dtype=float)
    sel = np.ones(t.shape, dtype=bool)
    if window is not None:
        sel = (t >= window[0]) & (t <= window[1])
    euler = np.asarray(euler, dtype=float)[sel]
    euler_des = np.asarray(euler_des, dtype=float)[sel]
    pos = np.asarray(pos, dtype=float)[sel]
    pos_des = np.asarray(pos_des, dtype=float)[sel]
    out = {}
    for i, name in enumerate(COLUMNS[:3]):
        out[name] = math.degrees(mean_error(euler[:, i], euler_des[:, i], angle=True))
    for i, name in enumerate(COLUMNS[3:]):
        out[name] = mean_error(pos[:, i], pos_des[:, i])
    return out


def format_table(rows: dict[str, dict[str, float]]) -> str:
    """Rows of mean errors as a text table in the layout of Table 6."""
    nw = max([14] + [len(name) for name in rows])
    head = f"{'strategy':<{nw}} {'ME_phi(deg)':>11} {'ME_theta(deg)':>13} {'ME_psi(deg)':>11} {'ME_X(m)':>9} {'ME_Y(m)':>9} {'ME_Z(m)':>9}"
    lines = [head]
    widths = (11, 13, 11, 9, 9, 9)
    for name, errs in rows.items():
        cells = []
        for col, w in zip(COLUMNS, widths):
            v = errs.get(col, math.nan)
            cells.append(f"{'-':>{w}}" if not math.isfinite(v) else f"{v:>{w}.4f}")
        lines.append(f"{name:<{nw}} " + " ".join(cells))
    return "\n".join(lines)
