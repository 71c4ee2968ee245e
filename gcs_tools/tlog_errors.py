"""The paper's mean errors (Eq. 45) from a .tlog of any MAVLink vehicle.

* phi, theta, psi: ATTITUDE (roll, pitch, yaw) against ATTITUDE_TARGET (its quaternion turned
  into Z-Y-X Euler angles by :func:`protocol.frames.mavlink_euler_from_quaternions`; targets
  with ATTITUDE_IGNORE set count as missing). Both sides are compared in MAVLink's
  convention. The paper's angles are ``(roll, -pitch, pi/2 - yaw)``
  (:func:`protocol.frames.mavlink_euler_to_paper`), so ``|phi - phi_d|``,
  ``|theta - theta_d|`` and the wrapped ``|psi - psi_d|`` equal the MAVLink differences
  exactly: the columns are the paper's phi, theta, psi errors.
* X, Y, Z: LOCAL_POSITION_NED against POSITION_TARGET_LOCAL_NED (targets with any of the
  X/Y/Z_IGNORE bits set, e.g. in attitude mode, count as missing). Reported as the paper's
  X (east), Y (north), Z (up): ``|x_E - x_E,d|`` is the NED y difference and so on
  (:func:`protocol.frames.ned_to_enu`).

Pairing: each actual sample is compared with the latest target stamped at or before it
(``time_boot_ms``); actual samples before the first target are skipped. The window
``(t_from, t_to)`` (seconds of ``time_boot_ms``, both ends included) selects actual samples.
Only the first vehicle in the log (or ``sysid``) is used.
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.errors import OperationError
from gcs_tools.tlog_read import read_fields
from protocol.dialect import mavlink as M
from protocol.frames import mavlink_euler_from_quaternions, ned_to_enu
from protocol.mean_error import COLUMNS, mean_error

POS_IGNORE = (M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE
              | M.POSITION_TARGET_TYPEMASK_Z_IGNORE)
ATT_IGNORE = M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE

SPEC = {
    "ATTITUDE": ["time_boot_ms", "roll", "pitch", "yaw"],
    "ATTITUDE_TARGET": ["time_boot_ms", "type_mask", "q[0]", "q[1]", "q[2]", "q[3]"],
    "LOCAL_POSITION_NED": ["time_boot_ms", "x", "y", "z"],
    "POSITION_TARGET_LOCAL_NED": ["time_boot_ms", "type_mask", "x", "y", "z"],
}
NEEDS = {"attitude": ("ATTITUDE", "ATTITUDE_TARGET"), "position": ("LOCAL_POSITION_NED", "POSITION_TARGET_LOCAL_NED")}


def pair_latest(t_actual: np.ndarray, t_target: np.ndarray) -> np.ndarray:
    """Index of the latest target at or before each actual time (-1 when there is none)."""
    order = np.argsort(t_target, kind="stable")
    idx = np.searchsorted(t_target[order], t_actual, side="right") - 1
    return np.where(idx >= 0, order[np.maximum(idx, 0)], -1)


def _paired(values: np.ndarray, idx: np.ndarray) -> np.ndarray:
    out = np.full((idx.size,) + values.shape[1:], np.nan)
    ok = idx >= 0
    out[ok] = values[idx[ok]]
    return out


def attitude_series(arrays) -> dict:
    """t (s), actual (N, 3) and paired target (N, 3) roll/pitch/yaw in MAVLink's convention."""
    a, tg = arrays["ATTITUDE"], arrays["ATTITUDE_TARGET"]
    actual = np.column_stack([a["roll"], a["pitch"], a["yaw"]])
    target = mavlink_euler_from_quaternions(np.column_stack([tg[f"q[{k}]"] for k in range(4)]))
    target[(tg["type_mask"].astype(np.int64) & ATT_IGNORE) != 0] = np.nan
    idx = pair_latest(a["time_boot_ms"], tg["time_boot_ms"])
    return {"t": a["time_boot_ms"] * 1e-3, "actual": actual, "target": _paired(target, idx)}


def position_series(arrays) -> dict:
    """t (s), actual (N, 3) and paired target (N, 3) positions, world ENU (the paper's X, Y, Z)."""
    p, tg = arrays["LOCAL_POSITION_NED"], arrays["POSITION_TARGET_LOCAL_NED"]
    actual = ned_to_enu(np.column_stack([p["x"], p["y"], p["z"]]).reshape(-1, 3))
    target = ned_to_enu(np.column_stack([tg["x"], tg["y"], tg["z"]]).reshape(-1, 3))
    target[(tg["type_mask"].astype(np.int64) & POS_IGNORE) != 0] = np.nan
    idx = pair_latest(p["time_boot_ms"], tg["time_boot_ms"])
    return {"t": p["time_boot_ms"] * 1e-3, "actual": actual, "target": _paired(target, idx)}


def _window(t, lo, hi) -> np.ndarray:
    sel = np.ones(t.shape, dtype=bool)
    if lo is not None:
        sel &= t >= lo
    if hi is not None:
        sel &= t <= hi
    return sel


def tlog_mean_errors(path, t_from: float | None = None, t_to: float | None = None, sysid: int | None = None) -> dict:
    """Eq. 45 per Table 6 column from a tlog.

    Returns ``{"mean_errors": {column: value or NaN}, "samples": {column: n}, "missing": {column:
    [message types]}, "sysid": ...}``. Raises :class:`OperationError` when no column can be computed.
    """
    arrays, info = read_fields(path, SPEC, sysid)
    counts = info["counts"]
    errors = {c: math.nan for c in COLUMNS}
    samples = {c: 0 for c in COLUMNS}
    missing: dict = {}
    for group, cols, build, angle in (("attitude", COLUMNS[:3], attitude_series, True),
                                      ("position", COLUMNS[3:], position_series, False)):
        absent = [m for m in NEEDS[group] if counts.get(m, 0) == 0]
        if absent:
            for c in cols:
                missing[c] = absent
            continue
        s = build(arrays)
        sel = _window(s["t"], t_from, t_to)
        for i, c in enumerate(cols):
            a, d = s["actual"][sel, i], s["target"][sel, i]
            ok = np.isfinite(a) & np.isfinite(d)
            samples[c] = int(ok.sum())
            if samples[c] == 0:
                missing[c] = [f"no {NEEDS[group][0]} sample with a usable {NEEDS[group][1]} at or before it"
                              + (" in the window" if t_from is not None or t_to is not None else "")]
                continue
            value = mean_error(a, d, angle=angle)
            errors[c] = math.degrees(value) if angle else value
    result = {"mean_errors": errors, "samples": samples, "missing": missing, "sysid": info["sysid"],
              "window_s": [t_from, t_to]}
    if all(not math.isfinite(v) for v in errors.values()):
        why = "; ".join(f"{c}: {', '.join(m)}" for c, m in missing.items())
        raise OperationError(f"{path}: no mean error computable ({why})")
    return result
