"""The motor chain from the log: each motor's thrust gain, the common thrust bias, the curve's exponent
and the actuation delay, fitted to the load-cell thrusts from the logged motor commands.

An input-output fit of one measured signal to another, not of the closed loop: whatever the
controllers did, the commands they sent are in SERVO_OUTPUT_RAW and the thrusts the motors gave in
HILMS_LOAD_CELLS. The model is the rig's own chain (rig_emulator/physics/hardware.py ``actuator_chain``,
``motor_thrust``; physics/rigid_body.py's motor lag; sensors/load_cell.py and
estimation/load_cell_filter.py), run at the physics rate:

1. the logged commands, linearly interpolated to the control updates and held between them (the
   firmware's zero-order hold), below the ESC dead-band 0 V;
2. the motor lag ``V' = (V_cmd - V) / tau`` (exactly as RK4 steps it), then the delay ``d``: both are
   linear, so they commute, and the delay is applied to the lagged voltage by linear interpolation:
   a **continuous** quantity, whose derivative is never zero (the rig rounds it to whole steps; the
   estimate is not);
3. each motor's true thrust ``g_i clip(F_p (V / V_p)^n + b, 0, F_max)`` (``V > 0``);
4. sampled as the load cells are, and smoothed by the firmware's IIR filter, read at the log's rows.

Parameters ``(g_1..g_4, b, n, d)`` by ``scipy.optimize.least_squares`` (a Gauss-Newton fit of a smooth
residual vector, its Jacobian at the optimum is what the covariance needs), started from the best
point of an explicit grid over the delay (0-60 ms in 2 ms) with the other parameters fitted at each:
the cost is not convex in the delay over a whole period of the chirps. Covariance: the HAC sandwich
(gcs_tools/identify/hac.py) on the Jacobian, the residuals of the four motors at one time as one score.
"""

from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import lfilter

from gcs_tools.identify.hac import bandwidth, hac_covariance
from gcs_tools.identify.rig_constants import RigConstants

NAMES = ("thrust_gain[0]", "thrust_gain[1]", "thrust_gain[2]", "thrust_gain[3]", "thrust_bias_N", "curve_exponent",
         "delay_s")
DELAY_GRID = np.arange(0.0, 0.0605, 0.002)
EXPONENT_GRID = np.arange(1.0, 3.01, 0.1)
SKIP_S = 3.0  # the filters' start-up at the beginning of the log is left out
BIAS_STARTS_N = (-0.25, -0.75)  # further starts of the first fit's thrust bias (fit_motor_chain)
GUARD_ITERATIONS = 4  # fits with the guards' rows predicted anew from the last (stops when they settle)
START_EXPONENT = 1.7  # the nominal chain's curve for the first prediction of the guards' rows
GUARD_K = 2.0  # noise sigmas of margin to the guards' thresholds (guard_rows)
HELD_TOL_N = 1e-3  # a reading repeated within this is a held one (float32 thrusts, inverted through the IIR)
HELD_K = 2.0  # ... where the chain's thrust is within this many noise sigmas of a guard's threshold
LC_STEP_N = 2.44 * 9.80665e-3  # the load cells' smallest step (sensors/load_cell.py)
LOWER = np.array([0.3, 0.3, 0.3, 0.3, -3.0, 0.5, 0.0])
UPPER = np.array([2.0, 2.0, 2.0, 2.0, 3.0, 4.0, 0.1])


@dataclass
class MotorChainFit:
    values: np.ndarray          # (7,) in NAMES order
    cov: np.ndarray             # (7, 7) HAC
    residuals: np.ndarray       # (n_rows, 4) load-cell thrust minus model, N
    predicted: np.ndarray       # (n_rows, 4) the model's filtered thrusts, N
    true_thrust: np.ndarray     # (n_rows, 4) the model's thrusts before the load cells (at the log rows), N
    model_voltage: np.ndarray   # (n_rows, 4) the motors' effective voltages (lagged, delayed), V
    lags: int
    rms: float
    used: np.ndarray            # (n_rows,) bool: the rows fitted
    model: "MotorChainModel"    # the chain of the log's commands the fit evaluated

    @property
    def sigma(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))


def grid_origin(rc: RigConstants, *times: np.ndarray) -> float:
    """Where the fine grid of a log starts: a step on which both a control update and a load-cell sample
    fall (the rig counts both from its step 0), at or before the first of ``times`` (s)."""
    period = rc.dt * math.lcm(rc.ctrl_div, rc.lc_decim)
    return math.floor(min(float(x[0]) for x in times) / period + 1e-9) * period


def cell_sample_index(rc: RigConstants, t0: float, t_cells: np.ndarray, n_samples: int) -> np.ndarray:
    """The load-cell sample (counted from the grid origin ``t0``) each row's reading comes from: the last
    at or before its stamp ``t_cells`` (a log that stamps the readings with the row's time gives the same)."""
    period = rc.dt * rc.lc_decim
    return np.clip(np.floor((t_cells - t0) / period + 1e-6).astype(np.int64), 0, n_samples - 1)


class MotorChainModel:
    """The chain of the module doc for one log's commands (precomputed once, evaluated per parameter)."""

    def __init__(self, t: np.ndarray, v_cmd: np.ndarray, rc: RigConstants, t_cmd: np.ndarray | None = None,
                 t_cells: np.ndarray | None = None):
        """``t`` the rows' times, ``v_cmd`` the commands each row carries; ``t_cmd`` / ``t_cells`` when the
        commands and the load-cell readings were taken (default: the rows' times)."""
        self.rc = rc
        dt = rc.dt
        t_cmd = t if t_cmd is None else t_cmd
        t_cells = t if t_cells is None else t_cells
        self.t0 = grid_origin(rc, t, t_cmd, t_cells)
        k_rows = np.round((t - self.t0) / dt).astype(np.int64)
        k_cmd, first = np.unique(np.round((t_cmd - self.t0) / dt).astype(np.int64), return_index=True)
        n_fine = int(max(k_rows[-1], k_cmd[-1])) + 1
        kf = np.arange(n_fine)
        k_ctrl = (kf // rc.ctrl_div) * rc.ctrl_div  # the control update each step holds
        u = np.empty((n_fine, 4))
        for i in range(4):
            u[:, i] = np.interp(k_ctrl, k_cmd, v_cmd[first, i])
        u[u < rc.deadband] = 0.0
        if rc.tau_motor > 0.0:
            h = dt / rc.tau_motor
            a = 1.0 - h + h * h / 2.0 - h ** 3 / 6.0 + h ** 4 / 24.0  # RK4's amplification of V' = -V / tau
            # the voltage at step k is the state the sensors see before step k's command acts on it
            u_prev = np.vstack([u[:1], u[:-1]])
            m = lfilter([1.0 - a], [1.0, -a], u_prev, axis=0, zi=(a * u[:1]))[0]
        else:
            m = u
        self.m = m  # lagged voltage at every physics step, before the delay
        self.k_lc = np.arange(0, n_fine, rc.lc_decim)  # the load cells' sample steps
        self.row_in_lc = cell_sample_index(rc, self.t0, t_cells, self.k_lc.size)
        self.k_rows = k_rows

    def voltages(self, delay: float, steps: np.ndarray) -> np.ndarray:
        """Lagged voltage at ``steps`` after a delay of ``delay`` s (linear interpolation, held before 0)."""
        pos = steps - delay / self.rc.dt
        lo = np.clip(np.floor(pos).astype(np.int64), 0, self.m.shape[0] - 1)
        hi = np.clip(lo + 1, 0, self.m.shape[0] - 1)
        w = np.clip(pos - np.floor(pos), 0.0, 1.0)[:, None]
        out = (1.0 - w) * self.m[lo] + w * self.m[hi]
        out[pos < 0] = self.m[0]
        return out

    def thrust(self, p: np.ndarray, v: np.ndarray) -> np.ndarray:
        rc = self.rc
        g = p[0:4]
        bias, n = p[4], p[5]
        r = np.maximum(v, 0.0) / rc.v_pivot
        f = rc.f_pivot * r ** n + bias
        f = np.clip(f, 0.0, rc.f_ceiling)
        f[v <= 0.0] = 0.0
        return f * g

    def filtered(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(load-cell readings at the log rows, true thrusts at the log rows) for parameters ``p``."""
        x = self.thrust(p, self.voltages(p[6], self.k_lc))
        a = self.rc.lc_alpha
        y = lfilter([a], [1.0, -(1.0 - a)], x, axis=0, zi=((1.0 - a) * x[:1]))[0] if a > 0.0 else x
        return y[self.row_in_lc], self.thrust(p, self.voltages(p[6], self.k_rows))


def guard_rows(model: "MotorChainModel", p: np.ndarray, k: float | None = None) -> np.ndarray:
    """Rows whose filtered reading the firmware's load-cell guards may have touched, **predicted** by the
    chain at ``p`` (never chosen from the measured readings or the residuals, which would bias the fit).

    The guards (estimation/load_cell_filter.py) replace a raw reading by the last accepted one when it
    jumps by more than ``lc_jump_N`` from it or lies above ``lc_max_N``; the chain has no model of that
    (whether a reading trips depends on its noise). A load-cell sample is at risk where the chain's
    thrust jumps within ``k`` noise sigmas of the threshold since the last sample, or lies within ``k``
    sigmas of the upper bound; a row is left out while its filtered reading still remembers such a
    sample: the IIR's memory down to 1 % plus the guard's re-accept count.
    """
    k = GUARD_K if k is None else k
    rc = model.rc
    x = model.thrust(p, model.voltages(p[6], model.k_lc))
    sd = cell_noise_sd(rc, x)
    jump = np.abs(np.diff(x, axis=0, prepend=x[:1]))
    sdd = np.sqrt(sd ** 2 + np.vstack([sd[:1], sd[:-1]]) ** 2)
    risk = np.any((jump > rc.lc_jump_N - k * sdd) | (x > rc.lc_max_N - k * sd), axis=1)
    return rows_after(risk, model)


def _raw_readings(log, model: "MotorChainModel"):
    """The readings the firmware's IIR took in, inverted sample by sample from the filtered ones
    (``y_j = y_{j-1} + alpha (x_j - y_{j-1})``): (x, y) each (n_lc, 4), or None when the log's rows do not
    show every load-cell sample or there is no IIR to invert."""
    a = model.rc.lc_alpha
    n_lc = model.k_lc.size
    first = np.full(n_lc, -1)
    rows = np.arange(model.row_in_lc.size)
    ok = model.row_in_lc >= 0
    # the first row at or after each sample shows it (if no later sample came first)
    j, idx = np.unique(model.row_in_lc[ok], return_index=True)
    first[j] = rows[ok][idx]
    seen = first >= 0
    if not 0.0 < a < 1.0 or seen[1:].mean() < 0.98:
        return None
    y = np.full((n_lc, 4), np.nan)
    y[seen] = log.thrust[first[seen]]
    x = np.full((n_lc, 4), np.nan)
    x[1:] = y[:-1] + (y[1:] - y[:-1]) / a
    return x, y


def held_samples(log, model: "MotorChainModel", p: np.ndarray) -> np.ndarray | None:
    """Load-cell samples the firmware's guards held, **seen** in the log, or None when the log's rows do
    not show every sample (rows slower than the load cells: :func:`guard_rows` predicts them instead).

    The filtered reading is inverted sample by sample to the reading ``x_j`` the filter took in
    (:func:`_raw_readings`). A reading a guard rejected is replaced by the last accepted one
    (estimation/load_cell_filter.py), so it repeats it to the float's precision and, having been
    rejected, lies a guard's threshold from the thrust; a reading that repeats by chance (the 10-bit
    counts) lies within the noise of it. Held: repeated within :data:`HELD_TOL_N`, and the chain's thrust
    at ``p`` either within :data:`HELD_K` noise sigmas of the jump guard's threshold away from it or of the
    upper guard. (n_lc, 4) bool.
    """
    raw = _raw_readings(log, model)
    if raw is None:
        return None
    return _held(raw[0], model.thrust(p, model.voltages(p[6], model.k_lc)), model.rc)


def _held(x: np.ndarray, f: np.ndarray, rc: RigConstants) -> np.ndarray:
    """:func:`held_samples`' test on the readings ``x`` the filter took in and the chain's thrusts ``f``
    at the same samples, (n_lc, 4) each."""
    sd = cell_noise_sd(rc, f)
    # rejected: the reading jumped by more than the guard's threshold from the value now repeated, or lay
    # above the guard's ceiling
    far = (np.abs(x - f) > rc.lc_jump_N - HELD_K * sd) | (f > rc.lc_max_N - HELD_K * sd)
    repeat = np.zeros(x.shape, dtype=bool)
    repeat[1:] = np.abs(x[1:] - x[:-1]) <= HELD_TOL_N
    return np.nan_to_num(repeat & far, nan=False).astype(bool)


@dataclass
class RepairedCells:
    thrust: np.ndarray   # (n_rows, 4) filtered thrusts, N, with the held samples' readings replaced
    noise_var: np.ndarray  # (n_rows, 4) variance of their own noise, N^2 (none from a replaced sample)
    rows: np.ndarray     # (n_rows,) bool: rows whose value is defined
    held_share: float    # share of load-cell samples held in any cell


def repaired_cells(log, model: "MotorChainModel", p: np.ndarray) -> RepairedCells | None:
    """The load cells' filtered thrusts as if no guard had held a reading, for a balance that needs every
    row (gcs_tools/identify/torque_balance.py), or None where the log does not show every sample.

    A guard that holds a reading feeds the firmware's IIR the last accepted value instead; the filter's
    output then remembers it for about half a second (:func:`rows_after`), and where the thrust swings
    near the jump guard's threshold (a steep motor curve, a stiff controller) that is most of an armed
    flight. The readings the filter took in are known (:func:`_raw_readings`), so each held one is
    replaced by the chain's thrust at ``p`` (the fitted motor chain, within its noise of the truth) and the
    series filtered again: every other reading keeps its own value and noise. ``model``: the chain of the
    log's commands (the fit's, :attr:`MotorChainFit.model`)."""
    raw = _raw_readings(log, model)
    if raw is None:
        return None
    rc = model.rc
    x, y = raw
    f = model.thrust(p, model.voltages(p[6], model.k_lc))
    held = _held(x, f, rc)
    x = np.where(held, f, x)
    x[0] = y[0]
    if not np.isfinite(x).all():
        return None
    a = rc.lc_alpha
    yf = lfilter([a], [1.0, -(1.0 - a)], x, axis=0, zi=((1.0 - a) * y[:1]))[0]  # yf[0] = y[0]: x[0] is y[0]
    v_raw = (cell_noise_sd(rc, f) ** 2 + LC_STEP_N ** 2 / 12.0) * ~held
    b = (1.0 - a) ** 2
    vf = lfilter([a * a], [1.0, -b], v_raw, axis=0, zi=(b * (a / (2.0 - a)) * v_raw[:1]))[0]
    r = model.row_in_lc
    rows = r >= 0
    thrust = np.full((r.size, 4), np.nan)
    var = np.full((r.size, 4), np.nan)
    thrust[rows] = yf[r[rows]]
    var[rows] = vf[r[rows]]
    return RepairedCells(thrust=thrust, noise_var=var, rows=rows, held_share=float(np.any(held, axis=1).mean()))


def rows_after(samples: np.ndarray, model: "MotorChainModel") -> np.ndarray:
    """Rows whose filtered reading still remembers one of ``samples`` (n_lc,) bool: the IIR's memory down
    to 1 % plus the guard's re-accept count."""
    rc = model.rc
    a = rc.lc_alpha
    memory = (int(math.ceil(math.log(0.01) / math.log(1.0 - a))) if 0.0 < a < 1.0 else 1) + max(rc.lc_reaccept, 1)
    c = np.concatenate([[0], np.cumsum(samples)])
    i = np.arange(samples.size)
    dilated = (c[i + 1] - c[np.clip(i + 1 - memory, 0, samples.size)]) > 0
    return dilated[model.row_in_lc]


def excluded_rows(log, model: "MotorChainModel", p: np.ndarray) -> np.ndarray:
    """Rows the chain cannot explain because a guard held a reading: the held samples where the log shows
    every sample (:func:`held_samples`), else as the chain at ``p`` predicts them (:func:`guard_rows`)."""
    held = held_samples(log, model, p)
    if held is None:
        return guard_rows(model, p)
    return rows_after(np.any(held, axis=1), model)


def cell_noise_sd(rc: RigConstants, thrust: np.ndarray) -> np.ndarray:
    """Standard deviation (N) of one raw load-cell reading at the motors' ``thrust`` (N): the datasheet's
    floor plus the vibration that grows with rotor speed squared, i.e. with thrust (sensors/load_cell.py)."""
    return rc.lc_noise_floor_N + rc.lc_vibration_N * np.maximum(thrust, 0.0) / (rc.kf * rc.rotor_speed_hover ** 2)


def cell_noise_var(rc: RigConstants, thrust: np.ndarray) -> np.ndarray:
    """Variance (N^2) of a filtered load-cell reading's own noise at the motors' ``thrust`` (N): the
    datasheet's floor plus the vibration that grows with rotor speed squared (i.e. thrust,
    sensors/load_cell.py), the 10-bit step's rounding, through the IIR (``alpha / (2 - alpha)``)."""
    sig = cell_noise_sd(rc, thrust)
    quant = (LC_STEP_N ** 2) / 12.0
    a = rc.lc_alpha
    return (sig ** 2 + quant) * (a / (2.0 - a) if a > 0.0 else 1.0)


def _grid_start(model, use, y, base, fixed) -> np.ndarray:
    """The start of the fit: the best point of a grid over the delay (and the curve's exponent), where
    the chain without its clipping is linear in each motor's ``g_i`` and ``g_i b`` (one linear least
    squares per grid point and motor)."""
    rc = model.rc
    a = rc.lc_alpha
    delays = [fixed[6]] if 6 in fixed else DELAY_GRID
    exps = [fixed[5]] if 5 in fixed else EXPONENT_GRID
    best = (np.inf, base.copy())
    for d in delays:
        v = model.voltages(d, model.k_lc)
        on = (v > 0.0).astype(float)
        r = np.maximum(v, 0.0) / rc.v_pivot
        h_on = lfilter([a], [1.0, -(1.0 - a)], on, axis=0, zi=((1.0 - a) * on[:1]))[0][model.row_in_lc][use]
        for n in exps:
            x = rc.f_pivot * r ** n * on
            h_x = lfilter([a], [1.0, -(1.0 - a)], x, axis=0, zi=((1.0 - a) * x[:1]))[0][model.row_in_lc][use]
            cost = 0.0
            g = np.zeros(4)
            c = np.zeros(4)
            for i in range(4):
                A = np.column_stack([h_x[:, i], h_on[:, i]])
                sol, *_ = np.linalg.lstsq(A, y[:, i], rcond=None)
                g[i], c[i] = sol
                cost += float(np.sum((A @ sol - y[:, i]) ** 2))
            if cost < best[0]:
                p = base.copy()
                for i in range(4):
                    if i not in fixed:
                        p[i] = np.clip(g[i], LOWER[i], UPPER[i])
                if 4 not in fixed:
                    p[4] = np.clip(np.sum(c) / np.sum(g), LOWER[4], UPPER[4])
                p[5], p[6] = n, d
                best = (cost, p)
    return best[1]


def fit_motor_chain(log, rc: RigConstants, rows: np.ndarray | None = None, fixed: dict | None = None) -> MotorChainFit:
    """Fit the chain to ``log`` (a :class:`~gcs_tools.identify.sysid_log.SysidLog`); ``rows``: a boolean
    mask of the rows whose residuals count (default all); ``fixed``: {index in NAMES: value} held, not
    fitted (their variance is 0)."""
    model = MotorChainModel(log.t, log.v_cmd, rc, log.t_cmd, log.t_cells)
    use = log.t >= log.t[0] + SKIP_S
    if rows is not None:
        use &= rows
    fixed = dict(fixed or {})
    free = [i for i in range(7) if i not in fixed]
    base = np.array([1.0, 1.0, 1.0, 1.0, 0.0, 1.0, 0.0])
    for i, v in fixed.items():
        base[i] = v

    def full(q):
        p = base.copy()
        p[free] = q
        return p

    def resid(q):
        return (model.filtered(full(q))[0][use] - y).ravel()

    # where the firmware's guards may have held a reading the chain has no model of it: those rows are left
    # out, as the chain predicts them (first from a nominal chain for the grid, then from the fit itself)
    nominal = base.copy()
    for i, v in ((5, START_EXPONENT), (6, rc.delay_preset)):
        if i not in fixed:
            nominal[i] = v
    use0 = use.copy()
    use = use0 & ~excluded_rows(log, model, nominal)
    y = log.thrust[use]
    best = _grid_start(model, use, y, base, fixed)
    steps = np.array([1e-4 if i < 6 else 2e-3 for i in free])
    cov = np.zeros((7, 7))
    if not free:  # everything held: the residuals of the given chain
        e = resid(np.empty(0))
        lags = bandwidth(e, log.dt, groups=4)
        p = base
    else:
        q = best[free]
        for it in range(GUARD_ITERATIONS):
            again = use0 & ~excluded_rows(log, model, full(q))
            if it > 0 and np.array_equal(again, use):
                break
            use = again
            y = log.thrust[use]
            starts = [q]
            if it == 0 and 4 not in fixed:
                # a stopped motor's voltage decays towards 0 without reaching it, and the rig adds the bias
                # to any voltage above 0 (clipped at 0 thrust): the cost has a kink at a bias of 0, where a
                # fit that starts above it can stall; so it also starts from below, and the best is kept
                for b in BIAS_STARTS_N:
                    q2 = q.copy()
                    q2[free.index(4)] = b
                    starts.append(q2)
            sols = [least_squares(resid, q0, bounds=(LOWER[free], UPPER[free]), method="trf", x_scale="jac",
                                  xtol=1e-10, ftol=1e-10, diff_step=steps) for q0 in starts]
            sol = min(sols, key=lambda r: r.cost)
            q = sol.x
        p = full(sol.x)
        e = sol.fun
        lags = bandwidth(e, log.dt, groups=4)
        cov[np.ix_(free, free)] = hac_covariance(sol.jac, e, lags, groups=4)
    pred, true = model.filtered(p)
    return MotorChainFit(values=p, cov=cov, residuals=log.thrust - pred, predicted=pred, true_thrust=true,
                         model_voltage=model.voltages(p[6], model.k_rows),
                         lags=lags, rms=float(np.sqrt(np.mean(e ** 2))), used=use, model=model)
