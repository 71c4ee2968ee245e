"""Measure how the rig degrades under each fault (the figures of docs/how-to/faults.md).

Run from the repository root: ``python -m gcs_tools.studies faults [--seeds 0 1 2]``
(``--markdown FILE`` also writes the tables as a docs page, with the command and the machine).
``--false-trips`` instead flies every scenario preset with every strategy on both plants, with no
fault (seed 0, ``harmonic`` at 2 rad/s): whether the failsafe trips where nothing is wrong, and how
close the rest come (the largest roll/pitch tracking error, body rate, and what the health checks
rejected).
Every case is a headless run of a scenario preset with one config fault event at
``t = 5 s`` (``faults.events``); figures are taken from 5 s until the loss-of-control
failsafe trips (or the end of the run), and the worst over the seeds is printed:

* ``est``: the largest roll/pitch estimation error, |estimated - true| (deg);
* ``track``: the largest roll/pitch tracking error, |desired - true| (deg);
* ``yaw rate``: the largest |yaw rate| (deg/s);
* ``drift``: how far the rig's own virtual position (Eq. 1 from its sensors) is from the
  true virtual position at the end, minus the same without the fault (m; runs without a
  failsafe trip only);
* ``failsafe``: seconds from the fault to the failsafe and its cause (A attitude error,
  R body rate, E estimate invalid) per seed, or ``-``;
* ``after``: for runs that tripped, the largest body rate from 0.5 s after the trip to the
  end divided by the body rate 0.5 s after the trip (1.00: the motors are off and the
  rotation no longer grows), and the largest motor thrust at the end (N).
"""

from __future__ import annotations

import argparse

import numpy as np

from gcs_tools.studies.page import Page
from rig_emulator.api import simulate
from rig_emulator.control.supervisor import ALERT_ATTITUDE, ALERT_ESTIMATE, ALERT_NAMES, ALERT_RATE

T_FAULT = 5.0
HEAD = ("| case | est [deg] | track [deg] | yaw rate [deg/s] | drift [m] | failsafe | after |\n"
        "|---|---|---|---|---|---|---|")


def _events(device, indices, mode, magnitude):
    return [{"t": T_FAULT, "sensor": device, "index": i, "mode": mode, "magnitude": magnitude} for i in indices]


def _wrap_deg(a):
    return (a + 180.0) % 360.0 - 180.0


def _figures(result, baseline_drift):
    s = result.series
    t = s["t"]
    fs = s["failsafe"]
    tripped = fs.max() > 0
    i_trip = int(np.argmax(fs > 0)) if tripped else len(t)
    m = (t >= T_FAULT) & (np.arange(len(t)) < i_trip)
    true = np.degrees(s["euler_true"][m, :2])
    est = float(np.abs(_wrap_deg(np.degrees(s["euler"][m, :2]) - true)).max())
    track = float(np.abs(_wrap_deg(np.degrees(s["euler_des"][m, :2]) - true)).max())
    yaw_rate = float(np.degrees(np.abs(s["omega"][m, 2])).max())
    if not tripped:
        drift = float(np.linalg.norm(s["pos"][-1] - s["pos_true"][-1])) - baseline_drift
        return est, track, yaw_rate, drift, None, None
    cause = int(fs[i_trip])
    tag = "".join(c for bit, c in ((ALERT_ATTITUDE, "A"), (ALERT_RATE, "R"), (ALERT_ESTIMATE, "E")) if cause & bit)
    w = np.linalg.norm(s["omega"], axis=1)
    j = int(np.searchsorted(t, t[i_trip] + 0.5))
    after = (float(w[j:].max() / w[j]), float(s["thrust"][-1].max()))
    return est, track, yaw_rate, None, (float(t[i_trip]) - T_FAULT, tag), after


def case(scenario, strategy, events, seeds, extra=None):
    rows = []
    for seed in seeds:
        base = simulate(scenario, strategy=strategy, seed=seed, overrides=dict(extra or {}))
        bd = float(np.linalg.norm(base.series["pos"][-1] - base.series["pos_true"][-1]))
        r = simulate(scenario, strategy=strategy, seed=seed, overrides={"faults.events": events, **(extra or {})})
        rows.append(_figures(r, bd))
    est = max(r[0] for r in rows)
    track = max(r[1] for r in rows)
    yaw = max(r[2] for r in rows)
    drifts = [r[3] for r in rows if r[3] is not None]
    drift = f"{max(drifts, key=abs):+.2f}" if drifts else "-"
    trips = [r[4] for r in rows]
    fs = "-" if all(x is None for x in trips) else ", ".join("-" if x is None else f"{x[0]:.2f} s {x[1]}" for x in trips)
    afters = [r[5] for r in rows if r[5] is not None]
    after = (f"{max(a[0] for a in afters):.2f}, {max(a[1] for a in afters):.1g} N") if afters else "-"
    return f"| {est:.2f} | {track:.2f} | {yaw:.0f} | {drift} | {fs} | {after} |"


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies faults", description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a string config override on every case (e.g. control.allocation_priority=clip)")
    ap.add_argument("--motor-only", action="store_true", help="only the motor thrust-loss table")
    ap.add_argument("--false-trips", action="store_true",
                    help="no fault: every scenario preset with every strategy on both plants (seed 0)")
    ap.add_argument("--workers", type=int, default=2, help="processes for --false-trips (default %(default)s)")
    ap.add_argument("--markdown", metavar="FILE",
                    help="also write the tables to FILE, with the command and the machine")
    return ap


def main(argv=None) -> None:
    args = parser().parse_args(argv)
    seeds = args.seeds
    common = dict(kv.split("=", 1) for kv in args.set)
    if args.false_trips:
        out = Page(args.markdown, "No fault: every scenario preset at its own duration (`harmonic` at 2 rad/s) with "
                                  "every strategy, seed 0, on both plants.", workers=args.workers)
        _false_trips(args.workers, out)
        out.write()
        return
    out = Page(args.markdown, f"The default plant `hilms`, seeds {' '.join(map(str, seeds))}; runs in the calling "
                              "process.")
    if args.motor_only:
        _motor_table(seeds, common, out)
    else:
        _all_tables(seeds, common, out)
    out.write()


def _all_tables(seeds, common, out):
    head = HEAD
    imu_modes = (("stuck", 0.0), ("dead", 0.0), ("bias", 3000.0), ("noise", 50.0))

    out.print(f"**IMU modules** (hover, smc-flc, robust_mean ensemble; seeds {seeds})\n\n{head}")
    for n in (1, 2, 3):
        for mode, mag in imu_modes:
            ev = _events("imu", range(n), mode, mag)
            out.print(f"| {n} x {mode} {mag:g} |", case("hover", "smc-flc", ev, seeds, common)[2:])
    out.print(f"\n**IMU modules while moving** (harmonic attitude, smc-flc; seeds {seeds})\n\n{head}")
    for mode, mag in imu_modes:
        out.print(f"| 1 x {mode} {mag:g} |", case("harmonic", "smc-flc", _events("imu", [2], mode, mag), seeds, common)[2:])
    out.print(f"\n**The same, plain mean ensemble** (the paper's)\n\n{head}")
    for mode, mag in imu_modes:
        out.print(f"| 1 x {mode} {mag:g} |", case("harmonic", "smc-flc", _events("imu", [2], mode, mag), seeds,
                                               {**common, "estimation.ensemble": "mean"})[2:])

    out.print(f"\n**Load cells** (hover, smc-flc; seeds {seeds})\n\n{head}")
    for mode, mag in (("dead", 0.0), ("spike", 200.0), ("stuck", 0.0)):
        out.print(f"| cell 2 {mode} {mag:g} |", case("hover", "smc-flc", _events("load_cell", [2], mode, mag), seeds, common)[2:])

    _motor_table(seeds, common, out)


def _motor_table(seeds, common, out):
    out.print(f"\n**Motor 1 thrust loss** (hover; seeds {seeds}; {common or 'preset'})\n\n{HEAD}")
    for strategy in ("smc-flc", "flc", "pid"):
        for loss in (0.1, 0.2, 0.3, 0.5, 1.0):
            ev = _events("motor", [1], "thrust_loss", loss)
            out.print(f"| {strategy} {100 * loss:.0f} % |", case("hover", strategy, ev, seeds, common)[2:])


if __name__ == "__main__":
    main()


STRATEGIES = ("smc-flc", "smc", "flc", "pid")


def _no_fault(job, result) -> dict:
    """What a run without a fault says about false trips (a sweep's reduce: runs in the worker)."""
    s = result.series
    t, fs = s["t"], s["failsafe"]
    err = np.degrees(np.abs(s["euler_des"][:, :2] - s["euler_true"][:, :2])).max(axis=1)
    i = int(np.argmax(err))
    health = np.asarray(s["health"]).astype(np.int64)
    return {"trip": float(t[np.argmax(fs > 0)]) if fs.max() > 0 else None, "cause": int(fs.max()),
            "err": float(err[i]), "err_t": float(t[i]),
            "rate": float(np.degrees(np.linalg.norm(s["omega"], axis=1)).max()),
            "invalid": bool(s["estimate_invalid"].max() > 0),
            "imu": int(np.bitwise_or.reduce(health[:, 0])), "imu_share": float(np.mean(health[:, 0] != 0)),
            "cells": int(np.bitwise_or.reduce(health[:, 1])), "cells_share": float(np.mean(health[:, 1] != 0))}


def _rejected(mask: int, share: float) -> str:
    if mask == 0:
        return "-"
    which = ", ".join(str(k + 1) for k in range(mask.bit_length()) if mask >> k & 1)
    return f"{which} ({100 * share:.1f} %)"


def _false_trips(workers: int, out: Page) -> None:
    from pathlib import Path

    from rig_emulator.sweep import SimJob, run_jobs

    scenarios = sorted(p.stem for p in (Path(__file__).resolve().parents[2] / "rig_emulator" / "presets" /
                                        "scenarios").glob("*.toml"))
    for plant in ("hilms", "hilms-ideal"):
        jobs = [SimJob(sc, st, 0, airframe=plant, overrides=(("guidance.omega", 2.0),) if sc == "harmonic" else (),
                       label=f"{sc} {st}") for sc in scenarios for st in STRATEGIES]
        res = run_jobs(jobs, workers=workers, reduce=_no_fault)
        out.print(f"\n**`{plant}`**\n\n| scenario | strategy | failsafe | largest roll / pitch error (deg, at s) "
                  "| largest body rate (deg/s) | estimate invalid | IMU modules rejected (share of the run) "
                  "| load cells rejected (share) |\n|---|---|---|---|---|---|---|---|")
        for job, r in zip(jobs, res):
            sc, st = job.label.split(" ")
            cause = ", ".join(name for bit, name in ALERT_NAMES.items() if r["cause"] & bit)
            trip = f"{cause} at {r['trip']:.2f} s" if r["trip"] is not None else "-"
            out.print(f"| {sc} | {st} | {trip} | {r['err']:.1f} at {r['err_t']:.1f} | {r['rate']:.0f} "
                      f"| {'yes' if r['invalid'] else '-'} | {_rejected(r['imu'], r['imu_share'])} "
                      f"| {_rejected(r['cells'], r['cells_share'])} |")
