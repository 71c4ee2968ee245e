"""The paper's mean error, Eq. 45: ``ME = sum |x - x_des| / n``, for phi, theta, psi, X, Y, Z.

Shared by the rig (headless runs) and the ground tools (tlogs), so both give the same
numbers from the same samples. Angles are reported in degrees and positions in metres,
the layout of Table 6.

The sum is formed the same way however the samples arrive: in blocks of
:data:`BLOCK` consecutive (finite) samples, each summed by numpy, the block sums added in
order (:class:`BlockSum`). A run streamed in chunks (:class:`MeanErrorAccumulator`,
``rig-emulator simulate`` of any length in bounded memory) therefore gives the same bits as
the whole series at once (:func:`mean_errors`).
"""

from __future__ import annotations

import math

import numpy as np

COLUMNS = ("phi_deg", "theta_deg", "psi_deg", "x_m", "y_m", "z_m")

PAPER_TABLE_6 = {
    "flc": dict(zip(COLUMNS, (0.7460, 0.5472, 0.8652, 0.0724, 0.0607, 0.2279))),
    "smc-flc": dict(zip(COLUMNS, (0.5096, 0.4926, 0.8197, 0.0659, 0.0550, 0.2263))),
}


BLOCK = 4096


def _abs_differences(actual, desired, angle: bool) -> np.ndarray:
    """|actual - desired| where both are finite (wrapped into (-pi, pi] first with ``angle``)."""
    a = np.asarray(actual, dtype=float)
    d = np.asarray(desired, dtype=float)
    ok = np.isfinite(a) & np.isfinite(d)
    diff = a[ok] - d[ok]
    if angle:
        diff = (diff + math.pi) % (2.0 * math.pi) - math.pi
    return np.abs(diff)


class BlockSum:
    """A sum of values given in pieces that does not depend on how they were cut: full
    blocks of :data:`BLOCK` values are summed by numpy and added in order; the rest waits."""

    def __init__(self):
        self.total = 0.0
        self.count = 0
        self._pending = np.empty(0)

    def add(self, values: np.ndarray) -> None:
        v = np.concatenate((self._pending, values)) if self._pending.size else np.asarray(values, dtype=float)
        full = v.size - v.size % BLOCK
        for i in range(0, full, BLOCK):
            self.total += float(v[i : i + BLOCK].sum())
        self._pending = v[full:].copy()
        self.count += values.size

    def mean(self) -> float:
        """The mean of everything added (NaN when nothing was)."""
        if self.count == 0:
            return math.nan
        return (self.total + float(self._pending.sum())) / self.count


def mean_error(actual, desired, angle: bool = False) -> float:
    """Eq. 45 over the samples where both are finite; NaN when there are none.

    ``angle=True`` wraps the difference into (-pi, pi] first.
    """
    acc = BlockSum()
    acc.add(_abs_differences(actual, desired, angle))
    return acc.mean()


class MeanErrorAccumulator:
    """Table 6's mean errors over a series given in pieces (:meth:`add`), in constant memory;
    :meth:`result` equals :func:`mean_errors` of the whole series, bit for bit."""

    def __init__(self):
        self._sums = [BlockSum() for _ in COLUMNS]

    def add(self, euler, euler_des, pos, pos_des) -> None:
        """One piece: (n, 3) arrays of the attitude (rad) and position (m), actual and desired."""
        for i in range(3):
            for j, (a, d, angle) in enumerate(((euler, euler_des, True), (pos, pos_des, False))):
                self._sums[3 * j + i].add(_abs_differences(np.asarray(a)[:, i], np.asarray(d)[:, i], angle))

    def result(self) -> dict[str, float]:
        out = {}
        for i, name in enumerate(COLUMNS):
            v = self._sums[i].mean()
            out[name] = math.degrees(v) if i < 3 else v
        return out


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
