"""The measured signals of an identification log, on one time grid (``rig-gcs identify --tlog``, regression).

What a ground station's .tlog of the rig carries, read with pymavlink's dialect
(:func:`gcs_tools.tlog_read.read_fields`) and turned into SI and the paper's frames at this one place:

* SERVO_OUTPUT_RAW ``servo1_raw``..``servo4_raw`` (us): the motor voltage commands,
  ``V = (pwm - 1000) / 1000 x motors.voltage_max`` (rig_emulator/link/telemetry/units.py ``pwm_us``);
* HILMS_LOAD_CELLS ``thrust_n`` (N): the filtered load-cell thrusts (or NAMED_VALUE_FLOAT LC1_N..LC4_N);
* ATTITUDE roll, pitch, yaw (the rig's attitude estimate, turned into the paper's phi, theta, psi)
  and rollspeed, pitchspeed, yawspeed (body rates omega_B, FRD, rad/s).

The rows are the ATTITUDE messages, at the log's own rate; each takes the latest motor commands and
load-cell readings stamped at or before it (:func:`read_sysid_log`).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs_tools.errors import UsageError
from gcs_tools.tlog_read import read_fields
from protocol.frames import mavlink_euler_to_paper

SPEC = {
    "ATTITUDE": ["time_boot_ms", "roll", "pitch", "yaw", "rollspeed", "pitchspeed", "yawspeed"],
    "SERVO_OUTPUT_RAW": ["time_usec", "servo1_raw", "servo2_raw", "servo3_raw", "servo4_raw"],
    "HILMS_LOAD_CELLS": ["time_usec", "thrust_n[0]", "thrust_n[1]", "thrust_n[2]", "thrust_n[3]"],
}


@dataclass
class SysidLog:
    """One log's rows: time (s), motor voltage commands (n, 4) V, load-cell thrusts (n, 4) N,
    attitude estimate (n, 3) paper phi, theta, psi rad, body rates (n, 3) rad/s; and the stamps of the
    commands (``t_cmd``: the control update that computed them) and of the load-cell readings
    (``t_cells``: their sample) each row carries (s)."""

    path: str
    digest: str
    t: np.ndarray
    v_cmd: np.ndarray
    thrust: np.ndarray
    euler: np.ndarray
    omega: np.ndarray
    t_cmd: np.ndarray
    t_cells: np.ndarray

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.t)))

    @property
    def armed(self) -> np.ndarray:
        """Rows with any motor commanded (a disarmed rig commands 0 V to all four)."""
        return np.any(self.v_cmd > 0.0, axis=1)


#: a row takes the latest command and load-cell message stamped at or before it, if it is at most this old
STALE_US = 20_000


def read_sysid_log(path, voltage_max: float, t_from: float | None = None, t_to: float | None = None) -> SysidLog:
    """Read ``path`` (UsageError naming what is missing).

    The rows are the ATTITUDE messages; each takes the latest SERVO_OUTPUT_RAW and HILMS_LOAD_CELLS stamped
    at or before it (within :data:`STALE_US`). Each message is stamped with when its values were taken:
    a served rig's commands come from the last control update and its load-cell readings from the last
    sample, up to 2 and 5 ms before the message goes out; the identification uses those stamps."""
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"--tlog {path}: no such file")
    digest = hashlib.sha256(p.read_bytes()).hexdigest()
    arrays, info = read_fields(str(p), SPEC)
    for kind in SPEC:
        if not info["counts"].get(kind):
            raise UsageError(f"--tlog {path}: no {kind} messages (the regression needs ATTITUDE, SERVO_OUTPUT_RAW and "
                             "HILMS_LOAD_CELLS)")
    att = arrays["ATTITUDE"]
    srv = arrays["SERVO_OUTPUT_RAW"]
    lc = arrays["HILMS_LOAD_CELLS"]

    def unique(us, a, names):
        u, idx = np.unique(np.round(us).astype(np.int64), return_index=True)
        return u, np.column_stack([a[n][idx] for n in names])

    us_att, att_v = unique(att["time_boot_ms"] * 1000.0, att, ["roll", "pitch", "yaw", "rollspeed", "pitchspeed",
                                                               "yawspeed"])
    us_srv, pwm = unique(srv["time_usec"], srv, [f"servo{i}_raw" for i in range(1, 5)])
    us_lc, thrust = unique(lc["time_usec"], lc, [f"thrust_n[{i}]" for i in range(4)])

    def as_of(us):
        j = np.searchsorted(us, us_att, side="right") - 1
        ok = j >= 0
        ok[ok] = us_att[ok] - us[j[ok]] <= STALE_US
        return np.clip(j, 0, None), ok

    j_srv, ok_srv = as_of(us_srv)
    j_lc, ok_lc = as_of(us_lc)
    keep = ok_srv & ok_lc
    if keep.sum() < 100:
        raise UsageError(f"--tlog {path}: only {int(keep.sum())} ATTITUDE rows with a SERVO_OUTPUT_RAW and a "
                         f"HILMS_LOAD_CELLS at most {STALE_US // 1000} ms older")
    t = us_att * 1e-6
    if t_from is not None:
        keep &= t >= t_from
    if t_to is not None:
        keep &= t <= t_to
    e = att_v[keep]
    euler = np.column_stack(mavlink_euler_to_paper(e[:, 0], e[:, 1], e[:, 2]))
    v = np.clip((pwm[j_srv[keep]] - 1000.0) / 1000.0, 0.0, 1.0) * voltage_max
    return SysidLog(str(p), digest, t[keep], v, thrust[j_lc[keep]], euler, e[:, 3:6],
                    us_srv[j_srv[keep]] * 1e-6, us_lc[j_lc[keep]] * 1e-6)
