"""``rig-gcs identify --tlog run.tlog`` (method ``regression``, the default for a log without ``--params``):
every identifiable effect of the rig from one identification flight's log, each with its 95 % interval,
and a verdict on whether the model explains the log.

1. the motor chain from commands against load-cell thrusts (gcs_tools/identify/motor_chain.py);
2. the joint and the frame from the torque balance, and the random torque from what it leaves
   (gcs_tools/identify/torque_balance.py);
3. the model checks: held-out windows and the residual's whiteness (gcs_tools/identify/model_check.py).

Nothing is simulated: the fit reads the log and the base configuration (what is not estimated,
gcs_tools/identify/rig_constants.py), so its result does not depend on any noise realisation of ours.
``hold``: effects kept at the base configuration's value instead of estimated (``--hold``), e.g. when
the flight could not excite them, and for the calibration study's mismatched cases.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from gcs_tools.identify import model_check as MC
from gcs_tools.identify.plausible import range_findings
from gcs_tools.identify.motor_chain import cell_noise_var, fit_motor_chain
from gcs_tools.identify.rig_constants import rig_constants
from gcs_tools.identify.sysid_log import read_sysid_log
from gcs_tools.identify.torque_balance import fit_torque_balance
from rig_emulator.physics.motors import GRAM_FORCE_N

# what --hold takes: effect -> (motor chain indices, torque balance indices)
HOLDABLE = {
    "thrust_gain": ((0, 1, 2, 3), ()),
    "thrust_bias": ((4,), ()),
    "curve": ((5,), ()),
    "delay": ((6,), ()),
    "inertia": ((), (0, 1, 2)),
    "viscous": ((), (3, 4, 5)),
    "coulomb": ((), (6, 7, 8)),
    "cog": ((), (9, 10, 11)),
}


#: How much wider the estimates scatter about the truth than the HAC covariance says, measured by the
#: calibration study on study seed 0's draws (``rig-gcs identify --calibration-study 20``, its column
#: "scatter / sigma" times the scale it ran with): 1.3-1.9 for the motor chain, 1.9-3.2 for the torque
#: balance, 1.1-1.4 for the random torque's level. The covariance is built from the residuals, which carry
#: the load cells' noise; it cannot see the errors of the regressors themselves (the attitude and the body
#: rates the balance is written in, the commands between two log rows), which also move the estimates. As
#: aircraft identification scales its Cramer-Rao bounds to the scatter of repeated manoeuvres (Morelli &
#: Klein, *Aircraft System Identification*, ch. 6), the intervals are widened by the largest of each
#: (rounded up); the study checks them on draws and noise seeds of its own (``--study-seed``), and the
#: blind test in the suite on others.
INTERVAL_SCALE_CHAIN = 2.0
INTERVAL_SCALE_BALANCE = 3.2
INTERVAL_SCALE_NOISE = 1.5

NONNEGATIVE = ("joint.viscous", "joint.coulomb", "disturbance.torque_noise", "control.actuation_delay")


@dataclass
class Estimate:
    key: str          # the configuration key (rig-emulator params)
    value: float
    lo: float         # 95 % interval
    hi: float
    unit: str
    how: str
    held: bool = False


@dataclass
class RegressionResult:
    estimates: list
    findings: list
    worst: dict
    whiteness: dict
    wall_s: float
    rows_used: dict = field(default_factory=dict)
    log_path: str = ""

    @property
    def explained(self) -> bool:
        return not self.findings

    def get(self, key: str) -> Estimate:
        return next(e for e in self.estimates if e.key == key)


def _held_values(cfg, rc, hold):
    mf, tb = {}, {}
    for h in hold:
        if h not in HOLDABLE:
            raise ValueError(f"--hold {h!r}: choose from {', '.join(HOLDABLE)}")
        mi, ti = HOLDABLE[h]
        for i in mi:
            mf[i] = (list(cfg["motors.thrust_gain"]) + [cfg["motors.thrust_bias_grf"] * GRAM_FORCE_N,
                                                         cfg["motors.curve_exponent"], cfg["control.actuation_delay"]])[i]
        for j in ti:
            tb[j] = ([cfg["airframe.ixx"], cfg["airframe.iyy"], cfg["airframe.izz"]] + list(cfg["joint.viscous"])
                     + list(cfg["joint.coulomb"]) + [rc.mass * c for c in cfg["joint.cog_offset"]])[j]
    return mf, tb


def identify_log(path, cfg, hold=(), t_from=None, t_to=None) -> RegressionResult:
    """Identify everything the regression sees in the log at ``path``; ``cfg`` is the base configuration."""
    t0 = time.perf_counter()
    rc = rig_constants(cfg)
    log = read_sysid_log(path, rc.v_max, t_from, t_to)
    mfix, tfix = _held_values(cfg, rc, hold)
    mf = fit_motor_chain(log, rc, fixed=mfix)
    tf = fit_torque_balance(log, rc, mf, fixed=tfix)
    z = 1.96 * INTERVAL_SCALE_CHAIN
    est = []
    ms = mf.sigma
    how_m = f"motor chain: commands vs load cells, least squares, HAC 95 % x{INTERVAL_SCALE_CHAIN:g}"
    for i in range(4):
        est.append(Estimate(f"motors.thrust_gain[{i}]", mf.values[i], mf.values[i] - z * ms[i], mf.values[i] + z * ms[i],
                            "", how_m, 0 in mfix))
    b = mf.values[4] / GRAM_FORCE_N
    sb = ms[4] / GRAM_FORCE_N
    est.append(Estimate("motors.thrust_bias_grf", b, b - z * sb, b + z * sb, "gr.F", how_m, 4 in mfix))
    est.append(Estimate("motors.curve_exponent", mf.values[5], mf.values[5] - z * ms[5], mf.values[5] + z * ms[5], "",
                        how_m, 5 in mfix))
    # the rig applies the delay in whole physics steps: any setting within half a step of the identified
    # delay acts the same, so the interval of the setting is wider by that half step
    half_step = 0.5 * rc.dt
    est.append(Estimate("control.actuation_delay", mf.values[6], max(mf.values[6] - z * ms[6] - half_step, 0.0),
                        mf.values[6] + z * ms[6] + half_step, "s",
                        how_m + " (continuous delay; the interval adds half a physics step)", 6 in mfix))
    tsig = np.sqrt(np.diag(tf.cov))
    z = 1.96 * INTERVAL_SCALE_BALANCE
    how_t = f"torque balance: filtered Eq. 3 regression, weighted, HAC 95 % x{INTERVAL_SCALE_BALANCE:g}"
    for j, key in enumerate(("airframe.ixx", "airframe.iyy", "airframe.izz")):
        est.append(Estimate(key, tf.values[j], tf.values[j] - z * tsig[j], tf.values[j] + z * tsig[j], "kg m^2", how_t,
                            j in tfix))
    for a in range(3):
        j = 3 + a
        est.append(Estimate(f"joint.viscous[{a}]", tf.values[j], tf.values[j] - z * tsig[j], tf.values[j] + z * tsig[j],
                            "N m s/rad", how_t, j in tfix))
    for a in range(3):
        j = 6 + a
        est.append(Estimate(f"joint.coulomb[{a}]", tf.values[j], tf.values[j] - z * tsig[j], tf.values[j] + z * tsig[j],
                            "N m", how_t, j in tfix))
    for a in range(3):
        j = 9 + a
        v, s = tf.values[j] / rc.mass, tsig[j] / rc.mass
        est.append(Estimate(f"joint.cog_offset[{a}]", v, v - z * s, v + z * s, "m", how_t + " (moment / mass)", j in tfix))
    how_n = f"torque balance residual: variance minus the load cells' own, HAC 95 % x{INTERVAL_SCALE_NOISE:g}"
    for a in range(3):
        v, (lo, hi) = tf.noise_sigma[a], tf.noise_interval[a]
        est.append(Estimate(f"disturbance.torque_noise[{a}]", v, max(v - INTERVAL_SCALE_NOISE * (v - lo), 0.0),
                            v + INTERVAL_SCALE_NOISE * (hi - v), "N m", how_n))
    held_out, pred_var = tf.held_out(MC.WINDOW_S, log.t, INTERVAL_SCALE_BALANCE)
    f1, w1 = MC.torque_findings(log, held_out, tf.expected_var, tf.used, pred_var, tf.residuals)
    f2, w2 = MC.cell_findings(log, mf.residuals, cell_noise_var(rc, mf.true_thrust), mf.used)
    white = MC.whiteness(tf.residuals, tf.used, log.dt)
    findings = f1 + f2 + [MC.Finding(k + " (slow residual)", log.t[0], log.t[-1], v, MC.WHITE_LIMIT)
                          for k, v in white.items() if v > MC.WHITE_LIMIT] + range_findings(est)
    return RegressionResult(est, findings, {**w1, **w2}, white, time.perf_counter() - t0,
                            {"motor chain": float(mf.used.mean()), "torque balance": float(tf.used.mean())}, str(path))


def _fmt(v: float, unit: str) -> str:
    if unit == "s":
        return f"{v * 1e3:.2f} ms"
    return f"{v:.4g}" + (f" {unit}" if unit else "")


def report_lines(r: RegressionResult) -> list[str]:
    lines = [f"identification of {r.log_path} by regression ({r.wall_s:.1f} s; rows used: "
             + ", ".join(f"{k} {v:.0%}" for k, v in r.rows_used.items()) + ")",
             f"{'parameter':32s} {'estimate':>14s}   {'95 % interval':>28s}   how"]
    for e in r.estimates:
        if e.held:
            lines.append(f"{e.key:32s} {_fmt(e.value, e.unit):>14s}   {'(held: base configuration)':>28s}")
            continue
        iv = f"[{_fmt(e.lo, e.unit)}, {_fmt(e.hi, e.unit)}]"
        lines.append(f"{e.key:32s} {_fmt(e.value, e.unit):>14s}   {iv:>28s}   {e.how}")
    if r.findings:
        lines.append("MODEL CHECK: the model does not explain the log:")
        lines += ["  " + f.text() for f in r.findings]
        lines.append("  (an effect the model lacks or holds at a wrong value acts there: the estimates and their "
                     "intervals are not to be trusted)")
    else:
        worst = ", ".join(f"{k} {v:.1f}x" for k, v in sorted(r.worst.items()))
        lines.append(f"model check: the model explains the log (largest held-out window residual over the noise's: "
                     f"{worst})")
    return lines


def preset_text(r: RegressionResult, header: list[str]) -> str:
    """The estimated keys as a TOML preset for --config (list keys whole)."""
    # a key that cannot be negative gets 0 where its estimate is (the report keeps the estimate itself)
    vals = {e.key: (max(e.value, 0.0) if e.key.startswith(NONNEGATIVE) else e.value) for e in r.estimates
            if not e.held}
    lists: dict = {}
    scalars = {}
    for k, v in vals.items():
        if "[" in k:
            base, idx = k[:-1].split("[")
            lists.setdefault(base, {})[int(idx)] = v
        else:
            scalars[k] = v
    tables: dict = {}
    for k, v in scalars.items():
        sec, name = k.split(".", 1)
        tables.setdefault(sec, []).append(f"{name} = {v:.6g}")
    for k, d in lists.items():
        sec, name = k.split(".", 1)
        n = 4 if name == "thrust_gain" else 3
        if len(d) == n:
            tables.setdefault(sec, []).append(f"{name} = [{', '.join(f'{d[i]:.6g}' for i in range(n))}]")
    out = [f"# {h}" for h in header]
    for sec, items in tables.items():
        out.append(f"\n[{sec}]")
        out += items
    return "\n".join(out) + "\n"
