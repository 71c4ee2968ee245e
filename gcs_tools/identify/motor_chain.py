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
OUTLIER_K = 4.0
HIGH_SHARE = 0.88
HIGH_EPISODE_S = 0.3
LC_STEP_N = 2.44 * 9.80665e-3  # the load cells' smallest step (sensors/load_cell.py)
EPISODE_S = 0.3  # an outlier's episode: this long either side of it
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

    @property
    def sigma(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))


class MotorChainModel:
    """The chain of the module doc for one log's commands (precomputed once, evaluated per parameter)."""

    def __init__(self, t: np.ndarray, v_cmd: np.ndarray, rc: RigConstants):
        self.rc = rc
        dt = rc.dt
        k_rows = np.round((t - t[0]) / dt).astype(np.int64)
        n_fine = int(k_rows[-1]) + 1
        kf = np.arange(n_fine)
        k_ctrl = (kf // rc.ctrl_div) * rc.ctrl_div  # the control update each step holds
        u = np.empty((n_fine, 4))
        for i in range(4):
            u[:, i] = np.interp(k_ctrl, k_rows, v_cmd[:, i])
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
        self.row_in_lc = np.searchsorted(self.k_lc, k_rows, side="right") - 1  # last sample at or before each row
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


def high_rows(measured: np.ndarray, rc: RigConstants, dt: float) -> np.ndarray:
    """Rows within :data:`HIGH_EPISODE_S` of a load-cell thrust above :data:`HIGH_SHARE` of the ceiling."""
    bad = np.any(measured > HIGH_SHARE * rc.f_ceiling, axis=1)
    w = int(round(HIGH_EPISODE_S / dt))
    c = np.concatenate([[0], np.cumsum(bad)])
    i = np.arange(bad.size)
    return (c[np.clip(i + w + 1, 0, bad.size)] - c[np.clip(i - w, 0, bad.size)]) > 0


def cell_noise_var(rc: RigConstants, thrust: np.ndarray) -> np.ndarray:
    """Variance (N^2) of a filtered load-cell reading's own noise at the motors' ``thrust`` (N): the
    datasheet's floor plus the vibration that grows with rotor speed squared (i.e. thrust,
    sensors/load_cell.py), the 10-bit step's rounding, through the IIR (``alpha / (2 - alpha)``)."""
    sig = rc.lc_noise_floor_N + rc.lc_vibration_N * np.maximum(thrust, 0.0) / (rc.kf * rc.rotor_speed_hover ** 2)
    quant = (LC_STEP_N ** 2) / 12.0
    a = rc.lc_alpha
    return (sig ** 2 + quant) * (a / (2.0 - a) if a > 0.0 else 1.0)


def outlier_rows(resid: np.ndarray, use: np.ndarray, dt: float, sd: np.ndarray) -> np.ndarray:
    """Rows within :data:`EPISODE_S` of a residual beyond :data:`OUTLIER_K` robust sigmas (the median
    absolute deviation of the residuals over their expected noise ``sd``): a reading the guard held for
    longer than the chain predicts, a spike."""
    z = resid / sd
    running = use & np.all(sd > 1.5 * sd.min(axis=0), axis=1)  # the motors running: the noise model's scale
    ref = running if running.sum() > 100 else use
    r = np.abs(z - np.median(z[ref], axis=0))
    mad = 1.4826 * np.median(r[ref], axis=0)
    bad = np.any(r > OUTLIER_K * mad, axis=1) & use
    w = int(round(EPISODE_S / dt))
    c = np.concatenate([[0], np.cumsum(bad)])
    i = np.arange(bad.size)
    return (c[np.clip(i + w + 1, 0, bad.size)] - c[np.clip(i - w, 0, bad.size)]) > 0


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
    model = MotorChainModel(log.t, log.v_cmd, rc)
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

    # near the ceiling the firmware discards readings above it and its jump guard holds others: the
    # filtered reading is biased there, so those rows are left out
    use &= ~high_rows(log.thrust, rc, log.dt)
    y = log.thrust[use]
    best = _grid_start(model, use, y, base, fixed)
    steps = np.array([1e-4 if i < 6 else 2e-3 for i in free])
    cov = np.zeros((7, 7))
    if not free:  # everything held: the residuals of the given chain
        e = resid(np.empty(0))
        lags = bandwidth(e, log.dt, groups=4)
        p = base
    else:
        sol = least_squares(resid, best[free], bounds=(LOWER[free], UPPER[free]), method="trf", x_scale="jac",
                            xtol=1e-10, ftol=1e-10, diff_step=steps)
        p = full(sol.x)
        # where the load cells' jump guard held a reading (estimation/load_cell_filter.py) the chain has no
        # model of: an episode of residuals far beyond the rest, left out and fitted once more (twice)
        for _ in range(2):
            pred, true = model.filtered(p)
            again = use & ~outlier_rows(pred - log.thrust, use, log.dt, np.sqrt(cell_noise_var(model.rc, true)))
            if again.sum() == use.sum():
                break
            use = again
            y = log.thrust[use]
            sol = least_squares(resid, sol.x, bounds=(LOWER[free], UPPER[free]), method="trf", x_scale="jac",
                                xtol=1e-10, ftol=1e-10, diff_step=steps)
            p = full(sol.x)
        e = sol.fun
        lags = bandwidth(e, log.dt, groups=4)
        cov[np.ix_(free, free)] = hac_covariance(sol.jac, e, lags, groups=4)
    pred, true = model.filtered(p)
    return MotorChainFit(values=p, cov=cov, residuals=log.thrust - pred, predicted=pred, true_thrust=true,
                         model_voltage=model.voltages(p[6], model.k_rows),
                         lags=lags, rms=float(np.sqrt(np.mean(e ** 2))), used=use)
