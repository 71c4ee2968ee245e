"""The measured signals of an identification log, on one time grid (``rig-gcs identify --tlog``, regression).

What a ground station's .tlog of the rig carries, read with pymavlink's dialect
(:func:`gcs_tools.tlog_read.read_fields`) and turned into SI and the paper's frames at this one place:

* SERVO_OUTPUT_RAW ``servo1_raw``..``servo4_raw`` (us): the motor voltage commands,
  ``V = (pwm - 1000) / 1000 x motors.voltage_max`` (rig_emulator/link/telemetry/units.py ``pwm_us``);
* HILMS_LOAD_CELLS ``thrust_n`` (N): the filtered load-cell thrusts (or NAMED_VALUE_FLOAT LC1_N..LC4_N);
* ATTITUDE roll, pitch, yaw (the rig's attitude estimate, turned into the paper's phi, theta, psi)
  and rollspeed, pitchspeed, yawspeed (body rates omega_B, FRD, rad/s).

The messages of one telemetry row share their time stamp (``time_boot_ms`` / ``time_usec``); rows
whose three messages are all present are kept, at the log's own rate.
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
    attitude estimate (n, 3) paper phi, theta, psi rad, body rates (n, 3) rad/s."""

    path: str
    digest: str
    t: np.ndarray
    v_cmd: np.ndarray
    thrust: np.ndarray
    euler: np.ndarray
    omega: np.ndarray

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.t)))

    @property
    def armed(self) -> np.ndarray:
        """Rows with any motor commanded (a disarmed rig commands 0 V to all four)."""
        return np.any(self.v_cmd > 0.0, axis=1)


def read_sysid_log(path, voltage_max: float, t_from: float | None = None, t_to: float | None = None) -> SysidLog:
    """Read ``path`` (UsageError naming what is missing)."""
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
    ms_att = np.round(att["time_boot_ms"]).astype(np.int64)
    ms_srv = np.round(srv["time_usec"] / 1000.0).astype(np.int64)
    ms_lc = np.round(lc["time_usec"] / 1000.0).astype(np.int64)
    common = np.intersect1d(np.intersect1d(ms_att, ms_srv), ms_lc)
    if common.size < 100:
        raise UsageError(f"--tlog {path}: only {common.size} rows with ATTITUDE, SERVO_OUTPUT_RAW and "
                         "HILMS_LOAD_CELLS at the same time stamp")

    def pick(ms, a, names):
        _, idx = np.unique(ms, return_index=True)
        order = np.searchsorted(ms[idx], common)
        return np.column_stack([a[n][idx][order] for n in names])

    pwm = pick(ms_srv, srv, [f"servo{i}_raw" for i in range(1, 5)])
    thrust = pick(ms_lc, lc, [f"thrust_n[{i}]" for i in range(4)])
    e = pick(ms_att, att, ["roll", "pitch", "yaw"])
    w = pick(ms_att, att, ["rollspeed", "pitchspeed", "yawspeed"])
    euler = np.column_stack(mavlink_euler_to_paper(e[:, 0], e[:, 1], e[:, 2]))
    t = common * 1e-3
    keep = np.ones(t.size, dtype=bool)
    if t_from is not None:
        keep &= t >= t_from
    if t_to is not None:
        keep &= t <= t_to
    v = np.clip((pwm - 1000.0) / 1000.0, 0.0, 1.0) * voltage_max
    return SysidLog(str(p), digest, t[keep], v[keep], thrust[keep], euler[keep], w[keep])
