"""Fig. 12: hover (all attitude references zero) with torque shocks on the arms, SMC vs FLC.

Scenario ``hover-shocks`` (shocks of 1 N m for 50 ms at 3, 7, 11 and 15 s on arms 1-4),
logged at the control rate (500 Hz) so the chattering is seen. Per shock
(:func:`~gcs_tools.reproduce.metrics.shock_response`, attitude error = what the controller
sees minus the reference): the axis it disturbed, the peak deviation, the overshoot past
zero, and the settling time. Chattering, as Fig. 12 shows it (it plots the angles): RMS of the
roll and pitch errors above 5 Hz (:func:`~gcs_tools.reproduce.metrics.tilt_chattering_deg`),
which the verdict reads; next to it the RMS of the motor voltage commands above 5 Hz
(:func:`~gcs_tools.reproduce.metrics.hf_rms`).

Settling (:func:`~gcs_tools.reproduce.metrics.settling_about_final`) is the textbook one: the
time after which the response stays within 10 % of its deviation (at least 0.1 deg) about its
*final* value (the mean of the last second before the next shock; the last 0.2 s before it, where
the zero-phase filter already sees the next shock, left out), taken on the error below
the chattering cut-off (:func:`~gcs_tools.reproduce.metrics.low_part`, the complement of what
the chattering figure measures). The paper says the SMC both chatters and settles faster
(Fig. 12), so its settling is that of the response, not of the chattering; and an FLC without
integral action settles to its static offset, not to zero. The earlier measure (the raw error
into a band about zero) is still reported: neither controller can meet it on the hardware rig
(the SMC's 6-7 Hz relay oscillation is about +-0.25 deg, the FLC's static offset 0.3-0.5 deg,
both wider than the band), so it compared "not settled" with "not settled".
"""

from __future__ import annotations

import math

import numpy as np

from gcs_tools.reproduce import figures
from gcs_tools.reproduce.experiment import (NOT_REPRODUCED, PARTLY, REPRODUCED, Context, Section, Verdict, fmt,
                                            status_of, table)
from gcs_tools.reproduce.metrics import hf_rms, low_part, settling_about_final, shock_response, tilt_chattering_deg

NAME = "shocks"
TITLE = "Hover with shocks on the arms, SMC vs FLC"
PAPER = "Fig. 12"
STRATEGIES = ("smc", "flc")
LOG_HZ = 500.0
CUTOFF_HZ = 5.0
BAND_FRAC = 0.1
BAND_MIN_DEG = 0.1
FINAL_S = 1.0  # the final value: mean of the last second before the next shock
GUARD_S = 1.0 / CUTOFF_HZ  # the zero-phase low-pass reaches this far back from the next shock: left out
QUICK_S = 8.0
AXES = ("phi", "theta", "psi")


def jobs(ctx: Context) -> list:
    return [ctx.job("hover-shocks", s, duration=QUICK_S if ctx.quick else None,
                   overrides={"sim.log_rate_hz": LOG_HZ}, columns=("t", "euler", "euler_des", "v_cmd"),
                   label=f"{NAME}/{s}") for s in STRATEGIES]


def responses(result) -> list:
    """The shock responses of one run (shocks that fall inside it)."""
    s = result.series
    t = s["t"]
    err = np.degrees(s["euler"] - s["euler_des"])
    times = sorted(sh["t"] for sh in result.job.config()["disturbance.shocks"] if sh["t"] < t[-1])
    ends = times[1:] + [float(t[-1])]
    return [shock_response(t, err, t0, t1, BAND_FRAC, BAND_MIN_DEG) for t0, t1 in zip(times, ends)]


def settling(result, resp) -> list:
    """Per shock: (settling time about the final value of the error below the chattering
    cut-off, that final value, the band)."""
    s = result.series
    t = s["t"]
    low = low_part(t, np.degrees(s["euler"] - s["euler_des"]), CUTOFF_HZ)
    out = []
    for x in resp:
        end = x.t_end - GUARD_S  # the filtered next shock (or the end of the record) starts before it
        out.append(settling_about_final(t, low[:, x.axis], x.t_shock, end, BAND_FRAC, BAND_MIN_DEG,
                                        min(FINAL_S, (end - x.t_shock) / 2.0)))
    return out


def _median(values) -> float:
    return float(np.median(np.asarray(values, dtype=float))) if len(values) else math.nan


def summarise(result) -> dict:
    """One run's figures: every shock's response and settling, their counts and medians, the mean
    overshoot and peak, and the chattering (what :func:`analyse` reports and ``rig-gcs identify
    --claims`` fits)."""
    resp = responses(result)
    sett = settling(result, resp)
    return {
        "shocks": [{"t_s": x.t_shock, "axis": AXES[x.axis], "peak_deg": x.peak, "settling_s": st[0],
                    "final_deg": st[1], "band_deg": st[2], "settling_to_zero_s": x.settling_s,
                    "window_s": x.t_end - x.t_shock, "overshoot_pct": x.overshoot_pct}
                   for x, st in zip(resp, sett)],
        "settled": sum(math.isfinite(st[0]) for st in sett),
        "median_settling_s": _median([st[0] for st in sett]),
        "settled_to_zero": sum(x.settled for x in resp),
        "median_settling_to_zero_s": _median([x.settling_s for x in resp]),
        "mean_overshoot_pct": float(np.mean([x.overshoot_pct for x in resp])) if resp else math.nan,
        "mean_abs_peak_deg": float(np.mean([abs(x.peak) for x in resp])) if resp else math.nan,
        "chattering_deg_rms": tilt_chattering_deg(result.series["t"], result.series["euler"],
                                                  result.series["euler_des"], CUTOFF_HZ),
        "chattering_v_rms": hf_rms(result.series["t"], result.series["v_cmd"], CUTOFF_HZ),
        "lambda_reading": result.job.config()["smc.lambda_reading"],
    }


def analyse(ctx: Context, results: list, live=None) -> Section:
    per = {r.job.strategy: summarise(r) for r in results}
    rows = []
    for strat in STRATEGIES:
        for x in per[strat]["shocks"]:
            settle = fmt(x["settling_s"], 2) if math.isfinite(x["settling_s"]) else \
                f"not settled in {fmt(x['window_s'], 1)} s"
            zero = fmt(x["settling_to_zero_s"], 2) if math.isfinite(x["settling_to_zero_s"]) else "not settled"
            rows.append([strat.upper(), fmt(x["t_s"], 1), x["axis"], fmt(x["peak_deg"], 2), fmt(x["final_deg"], 2),
                         settle, zero, fmt(x["overshoot_pct"], 1)])
    smc, flc = per["smc"], per["flc"]
    n = len(smc["shocks"])
    body = [
        f"Scenario `hover-shocks` (attitude references zero, {n} shocks of 1 N m for 50 ms on the arms), "
        f"{int(LOG_HZ)} Hz log. Settling (textbook): the attitude error below {CUTOFF_HZ:g} Hz (the chattering "
        f"removed) stays within max({BAND_FRAC:.0%} of its deviation, {BAND_MIN_DEG} deg) about its final value (mean "
        f"of the last {FINAL_S:g} s before the next shock) until the next shock; next to it the raw error into the "
        "same band about zero (a controller without integral action never settles to zero, a chattering one never "
        "into a band narrower than its chattering). Overshoot: largest excursion past zero after the peak, % of "
        f"the peak. Chattering: RMS of the roll and pitch errors above {CUTOFF_HZ:g} Hz (what Fig. 12 plots; the "
        f"verdict's figure), and of the four motor voltage commands above {CUTOFF_HZ:g} Hz.",
        "",
        table(["strategy", "shock t (s)", "axis", "peak (deg)", "final value (deg)", "settling (s)",
               "raw, about zero (s)", "overshoot (%)"], rows),
        "",
        table(["strategy", "shocks settled", "median settling", "mean overshoot (%)", "chattering (deg rms > 5 Hz)",
               "motor commands (V rms > 5 Hz)"],
              [[s.upper(), f"{per[s]['settled']}/{n}", _settle(per[s]["median_settling_s"]),
                fmt(per[s]["mean_overshoot_pct"], 1), fmt(per[s]["chattering_deg_rms"], 3),
                fmt(per[s]["chattering_v_rms"], 3)] for s in STRATEGIES]),
        "",
        "Paper (Fig. 12, no numbers): SMC returns faster after each shock; FLC shows no chattering and less overshoot.",
    ]
    verdicts = [_settling_verdict(smc, flc, n), chattering_verdict(smc, flc), _overshoot_verdict(smc, flc)]
    fig = _figure(ctx, results)
    return Section(NAME, TITLE, PAPER, "\n".join(body), [fig], per, verdicts)


def _settling_verdict(smc, flc, n) -> Verdict:
    a, b = smc["median_settling_s"], flc["median_settling_s"]
    ok = a < b
    ev = (f"settling about the final value, chattering removed: SMC settled after {smc['settled']}/{n} shocks "
          f"(median {_settle(a)}), FLC after {flc['settled']}/{n} (median {_settle(b)}); the raw error about zero: "
          f"SMC {smc['settled_to_zero']}/{n}, FLC {flc['settled_to_zero']}/{n}")
    if not ok and smc["settled"] < n and smc.get("lambda_reading") == "si":
        ev += "; with the paper's SMC gains read in SI (lambda = 0.17 1/s) the SMC recovers over seconds"
    return Verdict("smc_settles_faster", status_of(ok), ev)


def _settle(seconds: float) -> str:
    return f"{fmt(seconds, 2)} s" if math.isfinite(seconds) else "not settled before the next shock"


def chattering_verdict(smc, flc) -> Verdict:
    """Fig. 12's "FLC eliminates the chattering" from two runs' :func:`summarise`: the FLC's roll and
    pitch chattering under half the SMC's (under it: partly)."""
    a, b = smc["chattering_deg_rms"], flc["chattering_deg_rms"]
    status = REPRODUCED if b < 0.5 * a else (PARTLY if b < a else NOT_REPRODUCED)
    return Verdict("flc_no_chattering", status,
                   f"roll and pitch error RMS above {CUTOFF_HZ:g} Hz (what Fig. 12 plots): SMC {fmt(a, 3)} deg, "
                   f"FLC {fmt(b, 3)} deg; the motor commands' above {CUTOFF_HZ:g} Hz: SMC "
                   f"{fmt(smc['chattering_v_rms'], 3)} V, FLC {fmt(flc['chattering_v_rms'], 3)} V")


def _overshoot_verdict(smc, flc) -> Verdict:
    """The paper does not define its overshoot: both readings are tested, the excursion past
    zero after the peak (the textbook overshoot) and the peak deviation the shock causes."""
    a, b = smc["mean_overshoot_pct"], flc["mean_overshoot_pct"]
    pa, pb = smc["mean_abs_peak_deg"], flc["mean_abs_peak_deg"]
    readings = [b < a, pb < pa]
    status = REPRODUCED if all(readings) else (PARTLY if any(readings) else NOT_REPRODUCED)
    return Verdict("flc_less_overshoot", status,
                   f"overshoot past zero after the peak: SMC {fmt(a, 1)} %, FLC {fmt(b, 1)} % of the peak; peak "
                   f"deviation: SMC {fmt(pa, 2)} deg, FLC {fmt(pb, 2)} deg")


def _figure(ctx: Context, results) -> str:
    plt = figures.pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
    for col, r in enumerate(results):
        s = r.series
        t = s["t"]
        for i, name in enumerate(AXES):
            axes[0, col].plot(t, np.degrees(s["euler"][:, i]), label=name)
        axes[0, col].set_title(f"({'ab'[col]}) {r.job.strategy.upper()}: attitude")
        axes[0, col].set_ylabel("angle (deg)")
        axes[0, col].legend(loc="upper left")
        for m in range(4):
            axes[1, col].plot(t, s["v_cmd"][:, m], lw=0.5, label=f"motor {m + 1}")
        axes[1, col].set_ylabel("voltage command (V)")
        axes[1, col].set_xlabel("t (s)")
        axes[1, col].legend(loc="upper right", ncol=4)
    fig.suptitle("Fig. 12 (emulated): hover with shocks on the arms")
    fig.tight_layout()
    return figures.save(fig, ctx.out_dir, "fig12_shocks.png")
