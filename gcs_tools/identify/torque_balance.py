"""The joint and the frame from the log: inertia, joint friction (viscous, Coulomb) and the centre of
gravity's offset (lateral and pendulum, three axes) by linear regression on Eq. 3's torque balance, and
the random torque's level from what the balance leaves.

Eq. 3 with the effects of rig_emulator/physics/hardware.py, per body axis ``a``:

    T_a = I_a w'_a + (w x I w)_a + (w x (0, 0, Jr W_r))_a + c_v,a w_a + c_c,a tanh(w_a / w_s) - (r_cg x m g_B)_a - n_a

with ``T`` the motors' torque (A6: ``l (F4 - F2)``, ``l (F1 - F3)``, ``k_M (F1 - F2 + F3 - F4)``) and ``n``
the random torque. The load cells give the thrusts only through the firmware's IIR filter ``H``; so,
as one does with a filtered output, every term is passed through the same filter: ``H[T]`` is what
the log's load cells say, and ``H[w']`` is the difference quotient of ``H[w]`` (no differentiation
of a noisy signal). Where the firmware's jump guard held a reading, the filter took in the last
accepted value instead, and its output remembers that for half a second; a stiff loop on a steep motor
curve trips the guard often enough to leave almost no armed row untouched, so the held readings are
replaced by the fitted motor chain's thrust and the readings filtered again
(gcs_tools/identify/motor_chain.py, ``repaired_cells``). The body rates (ATTITUDE) are interpolated
to the load cells' sample times and filtered as they were; gravity in B,
``g_B = g (sin theta, cos theta sin phi, cos theta cos phi)``, from the attitude estimate smoothed with
the gyros after the flight (gcs_tools/identify/attitude_smoother.py). The balance is linear in
``(I_xx, I_yy, I_zz, c_v (3), c_c (3), m r_cg (3))``.

Weights: feasible generalised least squares. A first fit weights each axis by the inverse of its
residual spread; then each row by the inverse of the spread the noise model expects there (the random
torque grows with the rotor load, the load cells' vibration with the thrust), scaled per axis to the
residuals of the armed rows and of the disarmed ones separately (:func:`_row_weights`), twice, in a log
that shows every load-cell sample (rows at 200 Hz or faster; slower rows keep the axis weights). The
disarmed swings carry the friction and the pendulum with no motor torque and no random torque, and
weigh accordingly; armed, the random torque also moves the body rates the friction is written in, which
biases the friction read from the armed rows (the yaw viscous friction by 10-30 % of its range at the top of the
random torque's range, measured on logs of known truth) and the weights keep that out. The
covariance is HAC (gcs_tools/identify/hac.py) on the weighted rows.

Random torque: the residual of the balance is ``-H[n]`` plus the load cells' own noise. ``n`` is the
rig's first-order coloured noise (corner ``disturbance.torque_noise_corner_hz``, level ``sigma`` at hover
times the rotor load ``L``); its stationary variance after the sampling and ``H`` is
``kappa sigma^2 L^2`` (closed form below), the load cells' is known from their datasheet figures (none
from a replaced reading). So ``sigma_a^2 = sum(r^2 - v_lc) / (kappa sum L^2)`` over the armed rows, its
interval from the HAC variance of that mean.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from gcs_tools.identify.attitude_smoother import smoothed_attitude
from gcs_tools.identify.hac import bandwidth, hac_covariance, long_run_covariance
from gcs_tools.identify.motor_chain import cell_noise_var, cell_sample_index, grid_origin, repaired_cells
from gcs_tools.identify.rig_constants import RigConstants

NAMES = ("ixx", "iyy", "izz", "viscous[0]", "viscous[1]", "viscous[2]", "coulomb[0]", "coulomb[1]", "coulomb[2]",
         "cog_moment[0]", "cog_moment[1]", "cog_moment[2]")
SKIP_S = 3.0  # the filters' start-up at the beginning of the log is left out


@dataclass
class TorqueFit:
    values: np.ndarray        # (12,) NAMES order
    cov: np.ndarray           # (12, 12)
    residuals: np.ndarray     # (n_rows, 3) N m, filtered domain (NaN where not used)
    used: np.ndarray          # (n_rows,) bool
    lags: int
    noise_sigma: np.ndarray   # (3,) random torque at hover, N m
    noise_interval: np.ndarray  # (3, 2) 95 % interval
    load: np.ndarray          # (n_rows,) rotor load L
    lc_var: np.ndarray        # (n_rows, 3) the load cells' own noise variance in the residual
    X: np.ndarray             # (n_rows, 3, 12) regressors
    Y: np.ndarray             # (n_rows, 3) regressand (held parameters' terms taken out)
    free: list                # indices of NAMES estimated
    row_weight: np.ndarray    # (n_rows, 3) the weights of the last least-squares step
    kappa: float

    @property
    def expected_var(self) -> np.ndarray:
        """(n_rows, 3) the residual variance the noise model expects at each row."""
        return self.kappa * (self.noise_sigma[None, :] * self.load[:, None]) ** 2 + self.lc_var

    def held_out(self, window_s: float, t: np.ndarray, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """Residuals of each window of ``window_s`` predicted by the regression fitted without it, and the
        variance of that prediction (n_rows, 3) each.

        The prediction's variance is the fit's: ``x C x^T`` with ``C`` the covariance of the parameters
        fitted without the window, built as the sandwich of the whole fit with the bread of the rows
        left (the meat scaled to their number) and widened by ``scale`` (the intervals' scale,
        gcs_tools/identify/regression.py). A window that alone carries an effect (the yaw spin-down, the
        only place the yaw friction shows) is predicted poorly by the rest even with the right model;
        its variance says so, and the model check weighs the residual against it.
        """
        out = np.full(self.Y.shape, np.nan)
        pvar = np.full(self.Y.shape, np.nan)
        edges = np.arange(np.floor(t[0]), t[-1] + window_s, window_s)
        Xf = self.X[:, :, self.free]
        wt = self.row_weight
        k = len(self.free)
        Aall = (Xf[self.used] * wt[self.used][:, :, None]).reshape(-1, k)
        bread_all = Aall.T @ Aall
        cf = self.cov[np.ix_(self.free, self.free)]
        meat_all = bread_all @ cf @ bread_all
        n_all = self.used.sum()
        for a, b in zip(edges[:-1], edges[1:]):
            w = (t >= a) & (t < b)
            train = self.used & ~w
            if train.sum() < 100 or not np.any(w & self.used):
                continue
            A = (Xf[train] * wt[train][:, :, None]).reshape(-1, k)
            y = (self.Y[train] * wt[train]).ravel()
            beta = np.linalg.lstsq(A, y, rcond=None)[0]
            out[w] = self.Y[w] - Xf[w] @ beta
            bi = np.linalg.pinv(A.T @ A)
            c = bi @ (meat_all * (train.sum() / n_all)) @ bi * scale ** 2
            pvar[w] = np.einsum("rak,kl,ral->ra", Xf[w], c, Xf[w])
        return out, pvar


def _iir(x: np.ndarray, alpha: float) -> np.ndarray:
    if alpha <= 0.0:
        return x
    return lfilter([alpha], [1.0, -(1.0 - alpha)], x, axis=0, zi=((1.0 - alpha) * x[:1]))[0]


def noise_variance_factor(rc: RigConstants) -> float:
    """kappa: variance of H[n] over sigma^2 for the rig's AR(1) noise (held per physics step, sampled
    every ``lc_decim`` steps) through the IIR ``y += alpha (x - y)``."""
    rho = np.exp(-2.0 * np.pi * rc.noise_corner_hz * rc.dt) ** rc.lc_decim
    a = rc.lc_alpha
    if a <= 0.0:
        return 1.0
    b = 1.0 - a
    return float(a * a * (1.0 + b * rho) / ((1.0 - b * b) * (1.0 - b * rho)))


REWEIGHT = 2  # rounds of row weights after the first fit (each from the last round's residuals)


def _noise_level(res, armed, load, lc_var, kappa, dt):
    """The random torque's level at hover per axis from the residuals of the armed rows, and its 95 %
    interval: ``sigma_a^2 = sum(r^2 - v_lc) / (kappa sum L^2)``, the interval from the HAC variance."""
    sig = np.zeros(3)
    ci = np.zeros((3, 2))
    L2 = load[armed] ** 2
    for ax in range(3):
        z = res[armed, ax] ** 2 - lc_var[armed, ax]
        s2 = z.sum() / (kappa * L2.sum())
        u = z - kappa * s2 * L2
        lag_z = bandwidth(u, dt)
        var_s2 = long_run_covariance(u[:, None], lag_z)[0, 0] / (kappa * L2.sum()) ** 2
        half = 1.96 * np.sqrt(var_s2)
        sig[ax] = np.sqrt(max(s2, 0.0))
        # where the residual leaves less than the load cells' own noise (a quiet axis), the estimate is 0
        # and the interval reaches up to the estimate's own resolution, not to 0
        ci[ax] = np.sqrt(max(s2 - half, 0.0)), np.sqrt(max(s2 + half, half))
    return sig, ci


def _row_weights(res, used, armed, load, lc_var, kappa, sig):
    """Weights of the rows for feasible generalised least squares: one over the residual's spread the
    noise model expects at each row (the random torque grows with the rotor load, the load cells'
    vibration with the thrust), scaled per axis to what the residuals show, separately for the armed
    rows and the rest (a disarmed swing has no random torque and quiet load cells: its spread is the
    regressors' own errors)."""
    model = kappa * (sig[None, :] * load[:, None]) ** 2 + lc_var
    w = np.zeros_like(model)
    for grp in (armed, used & ~armed):
        if not grp.any():
            continue
        s = np.mean(res[grp] ** 2, axis=0) / np.mean(model[grp], axis=0)
        w[grp] = 1.0 / np.sqrt(s[None, :] * model[grp])
    return w


def fit_torque_balance(log, rc: RigConstants, motor_fit, rows: np.ndarray | None = None,
                       fixed: dict | None = None) -> TorqueFit:
    """Regress the torque balance of ``log``; ``motor_fit`` (gcs_tools/identify/motor_chain.py) gives the
    rotor load and speeds; ``rows``: boolean mask of rows that count (default: all after ``SKIP_S``);
    ``fixed``: {index in NAMES: value} held at that value, not estimated (variance 0)."""
    t = log.t
    dt_lc = rc.dt * rc.lc_decim
    t0 = grid_origin(rc, t, log.t_cmd, log.t_cells)
    t_lc = t0 + dt_lc * np.arange(int(np.floor((t[-1] - t0) / dt_lc + 1e-9)) + 1)
    idx = cell_sample_index(rc, t0, log.t_cells, t_lc.size)
    w = np.column_stack([np.interp(t_lc, t, log.omega[:, i]) for i in range(3)])
    euler = smoothed_attitude(t, log.euler, log.omega)
    phi = np.interp(t_lc, t, euler[:, 0])
    theta = np.interp(t_lc, t, euler[:, 1])
    gB = rc.g * np.column_stack([np.sin(theta), np.cos(theta) * np.sin(phi), np.cos(theta) * np.cos(phi)])
    a = rc.lc_alpha
    Hw = _iir(w, a)
    # the angular acceleration at each sample: the central difference, in step with the torque of that sample
    # (a one-sided one lags or leads it by half a sample, 2.5 ms, which reads as friction)
    dHw = np.gradient(Hw, dt_lc, axis=0)
    Htanh = _iir(np.tanh(w / rc.coulomb_smoothing), a)
    HgB = _iir(gB, a)
    Hwyz = _iir(w[:, 1] * w[:, 2], a)
    Hwzx = _iir(w[:, 2] * w[:, 0], a)
    Hwxy = _iir(w[:, 0] * w[:, 1], a)
    # rotor gyroscopic term from the motor model's true thrusts (Eq. 38), a known offset
    f_true = np.column_stack([np.interp(t_lc, t, motor_fit.true_thrust[:, i]) for i in range(4)])
    om = np.sqrt(np.maximum(f_true, 0.0) / rc.kf)
    jr = rc.rotor_inertia * (om[:, 0] - om[:, 1] + om[:, 2] - om[:, 3])
    Hgyro_x = _iir(w[:, 1] * jr, a)
    Hgyro_y = _iir(-w[:, 0] * jr, a)
    pick = lambda x: x[idx]  # noqa: E731
    # the load cells as if no guard had held a reading (the chain's thrust in place of each held one), so
    # that every row counts; a log that does not show every sample keeps the rows the chain explains
    rep = repaired_cells(log, motor_fit.model, motor_fit.values)
    y_lc = log.thrust if rep is None else rep.thrust
    T = np.column_stack([rc.arm * (y_lc[:, 3] - y_lc[:, 1]), rc.arm * (y_lc[:, 0] - y_lc[:, 2]),
                         rc.km * (y_lc[:, 0] - y_lc[:, 1] + y_lc[:, 2] - y_lc[:, 3])])
    n = t.size
    X = np.zeros((n, 3, 12))
    Y = T - np.column_stack([pick(Hgyro_x), pick(Hgyro_y), np.zeros(t_lc.size)[idx]])
    dW, HW, HT, G = pick(dHw), pick(Hw), pick(Htanh), pick(HgB)
    # inertia: I_a w'_a plus the Euler coupling (w x I w): x: (Izz - Iyy) wy wz, y: (Ixx - Izz) wz wx, z: (Iyy - Ixx) wx wy
    X[:, 0, 0] = dW[:, 0]
    X[:, 1, 1] = dW[:, 1]
    X[:, 2, 2] = dW[:, 2]
    X[:, 0, 2] += pick(Hwyz)
    X[:, 0, 1] -= pick(Hwyz)
    X[:, 1, 0] += pick(Hwzx)
    X[:, 1, 2] -= pick(Hwzx)
    X[:, 2, 1] += pick(Hwxy)
    X[:, 2, 0] -= pick(Hwxy)
    for ax in range(3):
        X[:, ax, 3 + ax] = HW[:, ax]
        X[:, ax, 6 + ax] = HT[:, ax]
    # -(r x m g_B): x: -(m1 gz - m2 gy), y: -(m2 gx - m0 gz), z: -(m0 gy - m1 gx)
    X[:, 0, 10] = -G[:, 2]
    X[:, 0, 11] = G[:, 1]
    X[:, 1, 11] = -G[:, 0]
    X[:, 1, 9] = G[:, 2]
    X[:, 2, 9] = -G[:, 1]
    X[:, 2, 10] = G[:, 0]
    used = (t >= t[0] + SKIP_S) & (motor_fit.used if rep is None else rep.rows)
    if rows is not None:
        used &= rows
    fixed = dict(fixed or {})
    free = [j for j in range(12) if j not in fixed]
    for j, v in fixed.items():
        Y = Y - X[:, :, j] * v
    Xu = X[used][:, :, free].reshape(-1, len(free))
    Yu = Y[used].ravel()
    load = rc.k_v * motor_fit.model_voltage.sum(axis=1) / (rc.mass * rc.g)
    v_cell = cell_noise_var(rc, motor_fit.true_thrust) if rep is None else rep.noise_var
    lc_var = np.column_stack([rc.arm ** 2 * (v_cell[:, 1] + v_cell[:, 3]), rc.arm ** 2 * (v_cell[:, 0] + v_cell[:, 2]),
                              rc.km ** 2 * v_cell.sum(axis=1)])
    kappa = noise_variance_factor(rc)
    armed = used & log.armed
    b = np.linalg.lstsq(Xu, Yu, rcond=None)[0]
    r = (Yu - Xu @ b).reshape(-1, 3)
    row_w = np.tile(1.0 / np.sqrt(np.mean(r ** 2, axis=0)), (n, 1))  # first: one weight per axis
    res = np.full((n, 3), np.nan)
    # then, where the log shows every load-cell sample, the rows' noise model; in slower rows (a ground
    # station's 100 Hz log) the regressors' own errors rule the armed rows, whose weight then falls so far
    # that the disarmed swings alone set the balance's scale through the inertia (0.84x in a served log)
    for k in range(1 + (REWEIGHT if rep is not None else 0)):
        if k:
            row_w = _row_weights(res, used, armed, load, lc_var, kappa, sig)
        wts = row_w[used].ravel()
        b = np.linalg.lstsq(Xu * wts[:, None], Yu * wts, rcond=None)[0]
        e = Yu - Xu @ b
        res[used] = e.reshape(-1, 3)
        sig, ci = _noise_level(res, armed, load, lc_var, kappa, log.dt)
    ew = e * wts
    lags = bandwidth(ew, log.dt, groups=3)
    cov = np.zeros((12, 12))
    cov[np.ix_(free, free)] = hac_covariance(Xu * wts[:, None], ew, lags, groups=3)
    beta = np.zeros(12)
    beta[free] = b
    for j, v in fixed.items():
        beta[j] = v
    return TorqueFit(values=beta, cov=cov, residuals=res, used=used, lags=lags, noise_sigma=sig, noise_interval=ci,
                     load=load, lc_var=lc_var, X=X, Y=Y, free=free, row_weight=row_w, kappa=kappa)
