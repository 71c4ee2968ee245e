"""A user's flight logs as identification targets (``rig-gcs identify --tlog run.tlog --scenario NAME``).

Each log (a .tlog of a real rig or of an emulated one, e.g. ``rig-emulator simulate --out
run.tlog`` or ``rig-gcs log``) comes with the scenario that was flown: a scenario preset, the
strategy, and the base configuration of the fit. The scenario is simulated with the fitted
parameters and its series compared, time-aligned, with the logged ones:

* ``attitude`` - ATTITUDE roll, pitch, yaw (turned into the paper's phi, theta, psi by
  :func:`protocol.frames.mavlink_euler_to_paper`) against the run's ``euler`` (what the rig
  reports: its estimate), in degrees, yaw differences wrapped;
* ``position`` - LOCAL_POSITION_NED (turned into world ENU by :func:`protocol.frames.ned_to_enu`)
  against the run's ``pos`` (the rig's own virtual position), in metres;
* ``load_cells`` - HILMS_LOAD_CELLS ``thrust_n`` (or, without it, NAMED_VALUE_FLOAT LC1_N..LC4_N)
  against the run's ``thrust_meas`` (the filtered load-cell thrusts), in newtons.

Time: the log's ``time_boot_ms`` / ``time_usec`` minus ``t_offset`` (the log time of the
scenario's t = 0; 0 for the emulator's logs) is the scenario's time. Both sides are averaged
over the same intervals of 1/``fit_hz`` s (the logged samples in an interval against the
run's rows, logged at ``sim.log_rate_hz``, in it): a boxcar low-pass that keeps what the
parameters shape (a response, a bias, a lag) and drops what no model can match sample by
sample (a sign-switching controller's chattering, sensor noise, which diverge between any two
runs that are not bit-identical). Each residual is the difference of the interval means
divided by the channel's scale (:data:`DEFAULT_SCALES`: 1 deg, 0.05 m, 0.1 N), so the
channels weigh alike; an interval the run does not reach (or a run that diverged) counts
:data:`MISSING_RESIDUAL` scales.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gcs_tools.errors import UsageError
from gcs_tools.identify.problem import Base, Problem, check_strategy
from gcs_tools.tlog_read import read_fields
from protocol.frames import mavlink_euler_to_paper, ned_to_enu
from rig_emulator.sweep import SimJob

CHANNELS = ("attitude", "position", "load_cells")
DEFAULT_SCALES = {"attitude": 1.0, "position": 0.05, "load_cells": 0.1}  # deg, m, N
UNITS = {"attitude": "deg", "position": "m", "load_cells": "N"}
COLUMN_OF = {"attitude": "euler", "position": "pos", "load_cells": "thrust_meas"}
MISSING_RESIDUAL = 100.0
DEFAULT_FIT_HZ = 10.0
LC_NAMES = ("LC1_N", "LC2_N", "LC3_N", "LC4_N")
SPEC = {
    "ATTITUDE": ["time_boot_ms", "roll", "pitch", "yaw"],
    "LOCAL_POSITION_NED": ["time_boot_ms", "x", "y", "z"],
    "HILMS_LOAD_CELLS": ["time_usec", "thrust_n[0]", "thrust_n[1]", "thrust_n[2]", "thrust_n[3]"],
    "NAMED_VALUE_FLOAT": list(LC_NAMES),
}


@dataclass(frozen=True)
class FlightLog:
    """One log and the scenario flown in it."""

    path: str
    scenario: str
    strategy: str = "smc-flc"
    duration: float | None = None  # simulated seconds (default: up to the last logged sample used)
    t_offset: float = 0.0  # log time (s of time_boot_ms) of the scenario's t = 0
    t_from: float | None = None  # window of scenario time used (s)
    t_to: float | None = None
    sysid: int | None = None


@dataclass
class LoggedSeries:
    """The samples of one log used in the fit, per channel: scenario time and values."""

    log: FlightLog
    digest: str  # SHA-256 of the file
    t: dict = field(default_factory=dict)  # channel -> (n,) scenario time of each interval's first sample
    bins: dict = field(default_factory=dict)  # channel -> (n,) interval index floor(t * fit_hz)
    values: dict = field(default_factory=dict)  # channel -> (n, k) interval means, paper frames / SI (attitude in
    # rad, yaw unwrapped)
    samples: dict = field(default_factory=dict)  # channel -> logged samples used
    messages: dict = field(default_factory=dict)  # channel -> message type read
    t_last: float = 0.0  # scenario time of the last logged sample used


def interval_means(t: np.ndarray, values: np.ndarray, fit_hz: float, bins: np.ndarray | None = None):
    """(interval indices, first time in each, mean of ``values`` in each) over intervals of 1/fit_hz s;
    with ``bins``, the means over exactly those intervals (NaN where ``t`` has no sample)."""
    b = np.floor(t * fit_hz + 1e-9).astype(np.int64)
    if bins is None:
        bins = np.unique(b)
    pos = np.searchsorted(bins, b)
    inside = (pos < bins.size) & (bins[np.minimum(pos, bins.size - 1)] == b)
    pos = pos[inside]
    count = np.bincount(pos, minlength=bins.size).astype(float)
    means = np.full((bins.size, values.shape[1]), np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        for i in range(values.shape[1]):
            means[:, i] = np.bincount(pos, weights=values[inside, i], minlength=bins.size) / count
    first = np.full(bins.size, np.nan)
    if pos.size:
        order = np.argsort(pos, kind="stable")
        starts = np.r_[0, np.flatnonzero(np.diff(pos[order])) + 1]
        first[pos[order][starts]] = t[inside][order][starts]
    return bins, first, means


def _select(t, values, log: FlightLog):
    t = t - log.t_offset
    ok = np.isfinite(t) & np.all(np.isfinite(values), axis=1) & (t >= 0.0)
    if log.t_from is not None:
        ok &= t >= log.t_from
    if log.t_to is not None:
        ok &= t <= log.t_to
    if log.duration is not None:
        ok &= t <= log.duration
    t, values = t[ok], values[ok]
    order = np.argsort(t, kind="stable")
    return t[order], values[order]


def read_log(log: FlightLog, channels, fit_hz: float) -> LoggedSeries:
    """The channels of ``log`` (UsageError naming the file when it is unreadable or lacks them)."""
    p = Path(log.path)
    if not p.is_file():
        raise UsageError(f"--tlog {p}: no such file")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise UsageError(f"--tlog {p}: cannot read ({exc.strerror})") from None
    arrays, info = read_fields(str(p), SPEC, log.sysid)
    counts = info["counts"]
    out = LoggedSeries(log, hashlib.sha256(data).hexdigest())
    missing = []
    for ch in channels:
        if ch == "attitude" and counts.get("ATTITUDE"):
            a = arrays["ATTITUDE"]
            phi, theta, psi = mavlink_euler_to_paper(a["roll"], a["pitch"], a["yaw"])
            t, v, msg = a["time_boot_ms"] * 1e-3, np.column_stack([phi, theta, psi]), "ATTITUDE"
        elif ch == "position" and counts.get("LOCAL_POSITION_NED"):
            a = arrays["LOCAL_POSITION_NED"]
            t = a["time_boot_ms"] * 1e-3
            v = ned_to_enu(np.column_stack([a["x"], a["y"], a["z"]]).reshape(-1, 3))
            msg = "LOCAL_POSITION_NED"
        elif ch == "load_cells" and counts.get("HILMS_LOAD_CELLS"):
            a = arrays["HILMS_LOAD_CELLS"]
            t, v = a["time_usec"] * 1e-6, np.column_stack([a[f"thrust_n[{i}]"] for i in range(4)])
            msg = "HILMS_LOAD_CELLS"
        elif ch == "load_cells" and all(n in arrays.get("NAMED_VALUE_FLOAT", {}) for n in LC_NAMES):
            nv = arrays["NAMED_VALUE_FLOAT"]
            n = min(nv[name].size for name in LC_NAMES)
            t = nv["LC1_N_ms"][:n] * 1e-3
            v = np.column_stack([nv[name][:n] for name in LC_NAMES])
            msg = "NAMED_VALUE_FLOAT LC1_N..LC4_N"
        else:
            missing.append(ch)
            continue
        ts, vs = _select(np.asarray(t, dtype=float), np.asarray(v, dtype=float), log)
        if ts.size == 0:
            missing.append(f"{ch} (no sample in the window)")
            continue
        if ch == "attitude":
            vs[:, 2] = np.unwrap(vs[:, 2])
        out.bins[ch], out.t[ch], out.values[ch] = interval_means(ts, vs, fit_hz)
        out.samples[ch], out.messages[ch] = int(ts.size), msg
        out.t_last = max(out.t_last, float(ts[-1]))
    if missing:
        need = {"attitude": "ATTITUDE", "position": "LOCAL_POSITION_NED",
                "load_cells": "HILMS_LOAD_CELLS or NAMED_VALUE_FLOAT LC1_N..LC4_N"}
        what = "; ".join(f"{m} ({need.get(m.split(' ')[0], '')})" for m in missing)
        raise UsageError(f"--tlog {p}: lacks the channel(s) {what}; choose others with --channels "
                         f"(it holds {', '.join(sorted(k for k, n in counts.items() if n)) or 'none of them'})")
    return out


class TlogProblem(Problem):
    """Flight logs against the same scenarios simulated."""

    kind = "tlog"

    def __init__(self, logs: list[FlightLog], base: Base, seed: int = 0, channels=CHANNELS,
                 scales: dict | None = None, fit_hz: float = DEFAULT_FIT_HZ, log_rate_hz: float | None = None):
        if not logs:
            raise UsageError("no flight log given (--tlog FILE)")
        channels = tuple(channels)
        bad = [c for c in channels if c not in CHANNELS]
        if bad or not channels:
            raise UsageError(f"--channels {','.join(bad) or '(none)'}: choose from {', '.join(CHANNELS)}")
        self.channels, self.seed, self.fit_hz = channels, seed, float(fit_hz)
        if not (math.isfinite(self.fit_hz) and self.fit_hz > 0):
            raise UsageError(f"--fit-hz {fit_hz!r}: must be > 0")
        self.scales = dict(DEFAULT_SCALES)
        for k, v in (scales or {}).items():
            if k not in CHANNELS:
                raise UsageError(f"--scale {k}: choose from {', '.join(CHANNELS)}")
            if not (math.isfinite(v) and v > 0):
                raise UsageError(f"--scale {k}={v!r}: must be > 0")
            self.scales[k] = float(v)
        self.logs = []
        for log in logs:
            check_strategy(log.strategy, f"--tlog {log.path}")
            self.logs.append(read_log(log, channels, self.fit_hz))
        templates = []
        for k, s in enumerate(self.logs):
            lg = s.log
            duration = lg.duration if lg.duration is not None else math.ceil((s.t_last + 0.02) * 100.0) / 100.0
            extra = {"sim.log_rate_hz": log_rate_hz} if log_rate_hz else {}
            templates.append(SimJob(lg.scenario, lg.strategy, seed=seed, duration=duration, overrides=extra,
                                    columns=("t",) + tuple(COLUMN_OF[c] for c in channels),
                                    label=f"tlog{k}/{Path(lg.path).name}"))
        super().__init__(templates, base)

    def context(self) -> dict:
        return {"kind": self.kind, "seed": self.seed, "channels": list(self.channels), "scales": self.scales,
                "fit_hz": self.fit_hz, "base": self.base.describe(),
                "logs": [{"sha256": s.digest, "scenario": s.log.scenario, "strategy": s.log.strategy,
                          "duration": s.log.duration, "t_offset": s.log.t_offset, "t_from": s.log.t_from,
                          "t_to": s.log.t_to, "sysid": s.log.sysid, "job": repr(t)}
                         for s, t in zip(self.logs, self.templates)]}

    def channel_residuals(self, logged: LoggedSeries, result) -> dict:
        """channel -> (n, k) residual of the interval means in the channel's unit (deg, m, N), NaN where
        the run has no row in an interval."""
        s = result.series
        t_sim = np.asarray(s["t"], dtype=float)
        out = {}
        for ch in self.channels:
            sim = np.asarray(s[COLUMN_OF[ch]], dtype=float)
            if ch == "attitude":
                sim = sim.copy()
                sim[:, 2] = np.unwrap(sim[:, 2])
            _, _, means = interval_means(t_sim, sim, self.fit_hz, logged.bins[ch])
            d = means - logged.values[ch]
            if ch == "attitude":
                d[:, 2] = (d[:, 2] + np.pi) % (2.0 * np.pi) - np.pi
                d = np.degrees(d)
            out[ch] = d
        return out

    def evaluate(self, results: list) -> tuple[np.ndarray, dict]:
        parts, metrics = [], {}
        for k, (logged, result) in enumerate(zip(self.logs, results)):
            for ch, d in self.channel_residuals(logged, result).items():
                r = d / self.scales[ch]
                bad = ~np.isfinite(r)
                metrics[f"log{k}.{ch}.rms_{UNITS[ch]}"] = (float(np.sqrt(np.mean(d[~bad] ** 2)))
                                                           if np.any(~bad) else math.nan)
                metrics[f"log{k}.{ch}.missing"] = int(bad.sum())
                r[bad] = MISSING_RESIDUAL
                parts.append(r.ravel())
        return np.concatenate(parts), metrics

    def summary(self, residuals: np.ndarray, metrics: dict) -> dict:
        rows = []
        for k, s in enumerate(self.logs):
            for ch in self.channels:
                rows.append({"log": s.log.path, "channel": ch, "message": s.messages[ch], "samples": s.samples[ch],
                             "intervals": int(s.bins[ch].size),
                             "rms": metrics.get(f"log{k}.{ch}.rms_{UNITS[ch]}", math.nan), "unit": UNITS[ch],
                             "scale": self.scales[ch], "missing": metrics.get(f"log{k}.{ch}.missing", 0)})
        return {"channels": rows, "n": int(residuals.size),
                "rms_scaled": float(np.sqrt(np.mean(residuals ** 2))) if residuals.size else math.nan}
