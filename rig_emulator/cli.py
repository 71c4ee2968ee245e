"""``rig-emulator``: the rig's command line.

* ``rig-emulator simulate --scenario NAME --strategy NAME --duration S --seed N [--out FILE]``
  runs a scenario headless, as fast as the machine allows, and prints Table 6's mean errors.
* ``rig-emulator params [--scenario NAME]`` lists every parameter with its value, unit and range.
* ``rig-emulator scenarios`` lists the scenario and airframe presets.
* ``rig-emulator serve [--mavlink URL ...] [--speedup X] ...`` (also ``rig-emulator`` with no
  subcommand) runs the rig and serves MAVLink (see :mod:`rig_emulator.link.serve`).

Exit codes: 0 success, 2 bad arguments or configuration.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from protocol.mean_error import PAPER_TABLE_6, format_table
from rig_emulator.config.loader import ConfigError, available, load_config, parse_override
from rig_emulator.config.schema import SCHEMA, STRATEGIES
from rig_emulator.link.serve_args import add_serve_args



def _add_config_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--airframe", default="hilms", help="airframe preset (Table 2): %(default)s")
    p.add_argument("--config", action="append", default=[], metavar="FILE", help="extra TOML parameter file (repeatable)")
    p.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="override one parameter, TOML value syntax (repeatable), e.g. --set smc.switching=boundary",
    )


def _overrides(args) -> dict:
    out = {}
    for text in args.set:
        key, value = parse_override(text)
        out[key] = value
    return out


def _write_series(result, path: Path) -> None:
    """Write the run's time series as .npz, .csv or a MAVLink .tlog (the messages the live rig streams)."""
    series = result.series
    if path.suffix == ".tlog":
        from rig_emulator.link.telemetry.tlog_export import export_tlog

        export_tlog(result, path)
        return
    if path.suffix == ".npz":
        np.savez_compressed(path, **series)
        return
    if path.suffix == ".csv":
        cols, names = [], []
        for name, arr in series.items():
            arr = np.asarray(arr)
            if arr.ndim == 1:
                cols.append(arr)
                names.append(name)
            else:
                for i in range(arr.shape[1]):
                    cols.append(arr[:, i])
                    names.append(f"{name}_{i}")
        np.savetxt(path, np.column_stack(cols), delimiter=",", header=",".join(names), comments="", fmt="%.9g")
        return
    raise ConfigError(f"--out {path}: unsupported file type {path.suffix!r}; use .npz, .csv or .tlog")


def _failsafe_summary(result) -> dict | None:
    """When and why the loss-of-control failsafe tripped in a headless run (None: it did not)."""
    from rig_emulator.simulation.faults import failsafe_cause_text

    fs = result.series["failsafe"]
    if not np.any(fs > 0):
        return None
    i = int(np.argmax(fs > 0))
    return {"t_s": float(result.series["t"][i]), "cause": failsafe_cause_text(int(fs[i])),
            "action": result.config["failsafe.action"]}


def cmd_simulate(args) -> int:
    from rig_emulator.simulation.run import Simulation

    overrides = _overrides(args)
    overrides["control.strategy"] = args.strategy
    overrides["sim.seed"] = args.seed
    if args.duration is not None:
        overrides["sim.duration"] = args.duration
    if args.omega is not None:
        overrides["guidance.omega"] = args.omega
    cfg = load_config(airframe=args.airframe, scenario=args.scenario, files=args.config, overrides=overrides)
    sim = Simulation(cfg)
    result = sim.run()
    errors = result.mean_errors()
    rows = {args.strategy: errors}
    if args.scenario == "helix" and args.strategy in PAPER_TABLE_6:
        rows[f"paper {args.strategy}"] = PAPER_TABLE_6[args.strategy]
    if args.json:
        print(json.dumps({"scenario": args.scenario, "strategy": args.strategy, "seed": args.seed,
                          "mean_errors": {k: (None if not math.isfinite(v) else v) for k, v in errors.items()},
                          "sim_time_s": result.sim_time_s, "wall_time_s": result.wall_time_s,
                          "real_time_factor": result.real_time_factor, "failsafe": _failsafe_summary(result)}))
    else:
        print(f"scenario {args.scenario}, strategy {args.strategy}, seed {args.seed}: "
              f"{result.sim_time_s:g} s simulated in {result.wall_time_s:.3f} s ({result.real_time_factor:.0f}x real time)")
        print("mean errors (Eq. 45):")
        print(format_table(rows))
        fs = _failsafe_summary(result)
        if fs is not None:
            what = "motors stopped, disarmed" if fs["action"] == "disarm" else "reported only"
            print(f"loss of control at t = {fs['t_s']:.2f} s ({fs['cause']}): {what} (docs/FAULTS.md)")
        if cfg["guidance.type"] == "waypoints":
            reached = result.reached_t
            done = int(np.isfinite(reached).sum())
            times = ", ".join("-" if not np.isfinite(t) else f"{t:.2f}" for t in reached)
            print(f"waypoints reached: {done}/{reached.size} at t = [{times}] s "
                  f"(switching radius {cfg['guidance.switching_radius']:g} m)")
    if args.out:
        _write_series(result, Path(args.out))
    return 0


def cmd_serve(args) -> int:
    from rig_emulator.link.serve import cmd_serve as serve

    return serve(args, _overrides(args))


def cmd_calibrate(args) -> int:
    """Run the IMU calibration procedure (Sec. 4-1) on the rig of this seed and store the result."""
    from rig_emulator.estimation.calibration_file import save_calibration
    from rig_emulator.simulation.sensing import Sensing

    overrides = _overrides(args)
    overrides["sim.seed"] = args.seed
    overrides["sensors.calibration"] = "levenberg-marquardt"
    overrides["sensors.calibration_file"] = ""
    cfg = load_config(airframe=args.airframe, files=args.config, overrides=overrides)
    sensing = Sensing(cfg, 1.0 / cfg["sim.physics_rate_hz"], np.random.SeedSequence(cfg["sim.seed"]))
    if args.out:
        out = Path(args.out)
    elif args.config:
        first = Path(args.config[0])
        out = first.with_name(first.stem + ".imu-calibration.json")
    else:
        out = Path("imu-calibration.json")
    save_calibration(out, sensing.imu_calibration)
    rms = sensing.imu_calibration.residual_rms
    print(f"calibrated {rms.shape[0]} IMU modules of the rig with seed {args.seed}; written to {out}")
    print("fit residual rms per module: gyro [deg/s], accel [m/s^2], mag [uT]")
    for m in range(rms.shape[0]):
        print(f"  module {m}: {math.degrees(rms[m, 0]):.4f}  {rms[m, 1]:.4f}  {rms[m, 2] * 1e6:.3f}")
    print(f"use it with: --set sensors.calibration_file={str(out)!r}")
    return 0


def cmd_params(args) -> int:
    cfg = load_config(airframe=args.airframe, scenario=args.scenario, files=args.config, overrides=_overrides(args))
    for key, spec in SCHEMA.items():
        unit = f" [{spec.unit}]" if spec.unit else ""
        rng = "" if spec.kind in ("table_list",) else f"  ({spec.describe_range()})"
        print(f"{key} = {cfg[key]!r}{unit}{rng}\n    {spec.doc}")
    return 0


def cmd_scenarios(args) -> int:
    print("scenarios:", ", ".join(available("scenarios")))
    print("airframes:", ", ".join(available("airframes")))
    print("strategies:", ", ".join(STRATEGIES))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rig-emulator", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("serve", help="run the rig and serve MAVLink (the default command); keeps parameters and "
                                     "the mission in ./rig-state; optional MAVLink 2 signing (see serve --help)")
    add_serve_args(p)
    _add_config_args(p)
    p.set_defaults(func=cmd_serve)

    p = sub.add_parser("simulate", help="run a scenario headless and print the mean errors")
    p.add_argument("--scenario", required=True, help="scenario preset (see `rig-emulator scenarios`)")
    p.add_argument("--strategy", default="smc-flc", choices=STRATEGIES)
    p.add_argument("--duration", type=float, help="simulated seconds (default: the scenario's)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--omega", type=float, help="harmonic frequency in rad/s (Eq. 44)")
    p.add_argument("--out", help="write the time series (.npz, .csv, or .tlog: the MAVLink messages the live rig streams)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    _add_config_args(p)
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("calibrate", help="run the IMU calibration procedure and store the result (Sec. 4-1)")
    p.add_argument("--seed", type=int, default=0, help="the rig (its sensors' turn-on errors) to calibrate")
    p.add_argument("--out", help="calibration file (default: next to the first --config, or ./imu-calibration.json)")
    _add_config_args(p)
    p.set_defaults(func=cmd_calibrate)

    p = sub.add_parser("params", help="list every parameter with its value and allowed range")
    p.add_argument("--scenario")
    _add_config_args(p)
    p.set_defaults(func=cmd_params)

    p = sub.add_parser("scenarios", help="list scenario, airframe and strategy names")
    p.set_defaults(func=cmd_scenarios)
    parser.subcommands = tuple(sub.choices)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or (argv[0] not in parser.subcommands and argv[0] not in ("-h", "--help")):
        argv = ["serve", *argv]  # plain `rig-emulator [options]` serves MAVLink
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ConfigError as exc:
        print(f"rig-emulator: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
