"""The rig firmware's supervisor: sensor health, estimate validity, loss-of-control failsafe.

It runs every ``div`` physics steps (``health.update_rate_hz``, 100 Hz by default, rounded to
a whole number of control periods), after the controller, on what the firmware has: the
estimators' rejections, the fused IMU vectors and the attitude the controllers flew on.
Everything it decides is plain data in :class:`SupervisorState`; the link layer turns it
into MAVLink health bits and STATUSTEXT, the step loop obeys the failsafe. Reading: the
paper reports no fault handling; this is the usual monitor of a flight controller.

Sensor health (only with the sensor models on):

* a module is *flagged* for a sensor kind (gyro, accel, mag) once the ensemble rejects it
  more than half of the time, the share averaged exponentially over ``reject_window``
  seconds, and cleared when that share falls below a tenth; likewise a load cell whose
  readings a guard rejects (jump, ceiling, floor; :mod:`rig_emulator.estimation.load_cell_filter`).
  Isolated rejections do not flag: healthy modules are rejected now and then at body rates
  of ~200 deg/s (their scale errors differ), healthy cells a few times a second (vibration
  noise tails against the 100 grF jump guard), so spikes the guards absorb go unflagged;
* the fused estimate of a kind is *inconsistent* when more than ``max_rejected`` modules
  (half of them) are rejected at once - no majority left to vote with - or when the fused
  accelerometer's magnitude leaves ``[accel_lo, accel_hi]`` (the rig cannot translate, so
  it reads about ``g``) or the fused magnetometer's leaves ``[mag_lo, mag_hi]`` (about the
  site's field); it is reported *invalid* (``flags[F_INVALID]``) with the same averaging and
  hysteresis as the flags, since aggressive manoeuvres (~200 deg/s) make the modules
  disagree for moments. Several modules failing alike (e.g. three stuck) can outvote the
  good ones without tripping either test: stated in docs/how-to/faults.md.

Loss of control (armed, ``fs_enabled``), each condition must hold without a break for
``hold_time`` to trip the failsafe:

* ``ALERT_ATTITUDE``: the roll or pitch error (desired minus the attitude the controllers
  use) exceeds ``att_limit``;
* ``ALERT_RATE``: the body rate magnitude exceeds ``rate_limit``;
* ``ALERT_ESTIMATE``: the attitude estimate (gyro or accel) is inconsistent while the
  controllers fly on it (``fs_estimator`` and estimated feedback).

On tripping the cause bits are latched in ``flags[F_FAILSAFE]`` with the time and the
errors; with ``fs_disarm`` the step loop then commands the motors to 0 V and the rig
disarms (otherwise it only reports). The latch is cleared by arming again.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.control.controller import OUT_ATT_DES

SupervisorParams = namedtuple(
    "SupervisorParams",
    "div share_alpha max_rejected accel_lo accel_hi mag_lo mag_hi "
    "fs_enabled fs_disarm fs_estimator att_limit rate_limit hold_time",
)
SupervisorState = namedtuple(
    "SupervisorState",
    [
        "imu_share",   # (n_modules, 3) share of the time each module is rejected, per kind (averaged)
        "cell_share",  # (n_cells,) share of the time each cell's readings are rejected
        "flags",      # (F_SIZE,) int64, F_* below
        "values",     # (V_SIZE,) float64, V_* below
    ],
)

# flags
F_GYRO = 0  # modules flagged for their gyro (bit m = module m)
F_ACCEL = 1
F_MAG = 2
F_CELLS = 3  # load cells flagged (bit i = cell i + 1)
F_INVALID = 4  # fused estimate invalid: INVALID_* bits
F_ALERTS = 5  # loss-of-control conditions beyond their limit now: ALERT_* bits
F_FAILSAFE = 6  # latched cause (ALERT_* bits of the conditions that tripped); 0: not tripped
F_SIZE = 7
# values
V_SINCE = 0  # 3: time each ALERT condition started to hold without a break (-1: not holding)
V_TRIP_T = 3  # time of the trip
V_TRIP_ATT = 4  # roll/pitch error at the trip (rad)
V_TRIP_RATE = 5  # body rate magnitude at the trip (rad/s)
V_ATT_ERR = 6  # the latest roll/pitch error (rad)
V_INVALID_SHARE = 7  # 3: share of the time each kind's fused estimate is inconsistent (averaged)
V_SIZE = 10

INVALID_GYRO = 1
INVALID_ACCEL = 2
INVALID_MAG = 4
ALERT_ATTITUDE = 1
ALERT_RATE = 2
ALERT_ESTIMATE = 4
ALERT_NAMES = {ALERT_ATTITUDE: "attitude error", ALERT_RATE: "body rate", ALERT_ESTIMATE: "attitude estimate invalid"}
FAILSAFE_ACTIONS = ("disarm", "report")


def supervisor_params(cfg, n_modules: int, gravity: float, field_T: float, ctrl_dt: float,
                      ctrl_div: int = 1) -> SupervisorParams:
    """Compiled-side parameters from the config's ``health.*`` and ``failsafe.*`` keys, the
    number of IMU modules, the site's gravity and earth-field magnitude, and the control
    period ``ctrl_dt`` of ``ctrl_div`` physics steps."""
    periods = max(1, int(round(1.0 / (cfg["health.update_rate_hz"] * ctrl_dt))))
    dt = periods * ctrl_dt
    acc_tol = cfg["health.accel_tolerance"]
    mag_tol = cfg["health.mag_tolerance"]
    return SupervisorParams(
        div=periods * ctrl_div,
        share_alpha=1.0 - math.exp(-dt / cfg["health.reject_window"]),
        max_rejected=n_modules // 2,
        accel_lo=(1.0 - acc_tol) * gravity,
        accel_hi=(1.0 + acc_tol) * gravity,
        mag_lo=(1.0 - mag_tol) * field_T,
        mag_hi=(1.0 + mag_tol) * field_T,
        fs_enabled=bool(cfg["failsafe.enabled"]),
        fs_disarm=cfg["failsafe.action"] == "disarm",
        fs_estimator=bool(cfg["failsafe.on_estimate_invalid"]),
        att_limit=math.radians(cfg["failsafe.attitude_error_deg"]),
        rate_limit=math.radians(cfg["failsafe.rate_limit_deg_s"]),
        hold_time=cfg["failsafe.hold_time"],
    )


def supervisor_state(n_modules: int, n_cells: int) -> SupervisorState:
    state = SupervisorState(np.zeros((n_modules, 3)), np.zeros(n_cells),
                            np.zeros(F_SIZE, dtype=np.int64), np.zeros(V_SIZE))
    reset_failsafe(state)
    return state


def reset_failsafe(state: SupervisorState) -> None:
    """Clear the latch and the condition timers (on arming)."""
    state.flags[F_ALERTS] = 0
    state.flags[F_FAILSAFE] = 0
    state.values[V_SINCE : V_SINCE + 3] = -1.0
    state.values[V_TRIP_T : V_ATT_ERR + 1] = 0.0


FLAG_ON = 0.5  # flagged above this share of the time rejected ...
FLAG_OFF = 0.1  # ... and healthy again below this one


@jit(inline="always")
def _share(share, rejected, alpha, flagged_before):
    """Update one unit's averaged rejected share; returns whether it is flagged now (hysteresis)."""
    share += alpha * ((1.0 if rejected else 0.0) - share)
    if share > FLAG_ON:
        return share, True
    if share < FLAG_OFF:
        return share, False
    return share, flagged_before != 0


@jit(inline="always")
def _flag_units(mask, share, col, alpha, flagged):
    """Average the rejections in ``mask`` into ``share[:, col]``; returns the new flagged mask."""
    out = 0
    for m in range(share.shape[0]):
        value, on = _share(share[m, col], (mask >> m) & 1, alpha, (flagged >> m) & 1)
        share[m, col] = value
        if on:
            out |= 1 << m
    return out


@jit(inline="always")
def _popcount(mask):
    n = 0
    while mask:
        n += mask & 1
        mask >>= 1
    return n


@jit(inline="always")
def _hold(t, active, since, i, hold_time):
    """Track how long condition ``i`` has held; True once it has held for ``hold_time``."""
    if not active:
        since[i] = -1.0
        return False
    if since[i] < 0.0:
        since[i] = t
    return t - since[i] >= hold_time - 1e-9


@jit(nrt=False)
def supervise(t, armed, simulate, estimated, phi, theta, wx, wy, wz, cout, ens_rejected, fused, cell_rejected,
              up, us):
    """One supervisor update at time ``t``; returns True when the failsafe trips now with
    ``fs_disarm`` (the caller then cuts the motors).

    Call it after a control update on every ``up.div``-th physics step.
    ``ens_rejected`` (3,) the ensemble's latest rejected-module masks per kind, ``fused``
    (3, 3) the fused IMU vectors [kind, axis] (SI), ``cell_rejected`` the load-cell guards'
    latest mask; ``phi, theta, wx, wy, wz`` the feedback the controllers used.
    """
    flags = us.flags
    v = us.values
    invalid = 0  # inconsistent now (the failsafe's input); flags[F_INVALID] is its averaged report
    if simulate:
        for s in range(3):
            flags[F_GYRO + s] = _flag_units(ens_rejected[s], us.imu_share, s, up.share_alpha, flags[F_GYRO + s])
            if _popcount(ens_rejected[s]) > up.max_rejected:
                invalid |= 1 << s
        a2 = fused[1, 0] * fused[1, 0] + fused[1, 1] * fused[1, 1] + fused[1, 2] * fused[1, 2]
        if a2 < up.accel_lo * up.accel_lo or a2 > up.accel_hi * up.accel_hi:
            invalid |= INVALID_ACCEL
        m2 = fused[2, 0] * fused[2, 0] + fused[2, 1] * fused[2, 1] + fused[2, 2] * fused[2, 2]
        if m2 < up.mag_lo * up.mag_lo or m2 > up.mag_hi * up.mag_hi:
            invalid |= INVALID_MAG
        reported = 0
        for s in range(3):
            value, on = _share(v[V_INVALID_SHARE + s], (invalid >> s) & 1, up.share_alpha,
                               (flags[F_INVALID] >> s) & 1)
            v[V_INVALID_SHARE + s] = value
            if on:
                reported |= 1 << s
        flags[F_INVALID] = reported
        cells = 0
        cs = us.cell_share
        before = flags[F_CELLS]
        for i in range(cs.shape[0]):
            value, on = _share(cs[i], (cell_rejected >> i) & 1, up.share_alpha, (before >> i) & 1)
            cs[i] = value
            if on:
                cells |= 1 << i
        flags[F_CELLS] = cells
    err = max(abs(cout[OUT_ATT_DES] - phi), abs(cout[OUT_ATT_DES + 1] - theta))
    v[V_ATT_ERR] = err
    if not (armed and up.fs_enabled) or flags[F_FAILSAFE] != 0:
        flags[F_ALERTS] = 0
        for i in range(3):
            v[V_SINCE + i] = -1.0
        return False
    rate = math.sqrt(wx * wx + wy * wy + wz * wz)
    est_bad = simulate and estimated and up.fs_estimator and (invalid & (INVALID_GYRO | INVALID_ACCEL)) != 0
    alerts = 0
    if err > up.att_limit:
        alerts |= ALERT_ATTITUDE
    if rate > up.rate_limit:
        alerts |= ALERT_RATE
    if est_bad:
        alerts |= ALERT_ESTIMATE
    flags[F_ALERTS] = alerts
    cause = 0
    since = v[V_SINCE : V_SINCE + 3]
    if _hold(t, alerts & ALERT_ATTITUDE != 0, since, 0, up.hold_time):
        cause |= ALERT_ATTITUDE
    if _hold(t, alerts & ALERT_RATE != 0, since, 1, up.hold_time):
        cause |= ALERT_RATE
    if _hold(t, alerts & ALERT_ESTIMATE != 0, since, 2, up.hold_time):
        cause |= ALERT_ESTIMATE
    if cause == 0:
        return False
    flags[F_FAILSAFE] = cause
    v[V_TRIP_T] = t
    v[V_TRIP_ATT] = err
    v[V_TRIP_RATE] = rate
    return up.fs_disarm
