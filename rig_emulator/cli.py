"""``rig-emulator``: the rig's command line.

* ``rig-emulator simulate --scenario NAME --strategy NAME --duration S --seed N [--out FILE]``
  runs a scenario headless, as fast as the machine allows, and prints Table 6's mean errors;
  ``--controller package.module:Name`` flies a controller plug-in (docs/how-to/your-controller.md).
* ``rig-emulator params [--scenario NAME] [--controller MODULE:NAME]`` lists every parameter with its value, unit and
  range, a controller plug-in's own ones (``controller.params.NAME``) with their defaults.
* ``rig-emulator scenarios`` lists the scenario and airframe presets.
* ``rig-emulator divergence --scenario NAME --seed N`` runs a scenario on both plants and prints how
  far the onboard position and the physics vehicle (SIM_STATE) part (docs/explanation/sim-state.md).
* ``rig-emulator hover-thrust`` flies the rig in attitude mode and prints the normalised collective
  thrust (SET_ATTITUDE_TARGET.thrust) that hovers, per plant (docs/how-to/attitude-thrust.md).
* ``rig-emulator serve [--mavlink URL ...] [--speedup X] ...`` (also ``rig-emulator`` with no
  subcommand) runs the rig and serves MAVLink (see :mod:`rig_emulator.link.serve`).

Exit codes: 0 success, 2 bad arguments or configuration, or a controller plug-in that failed.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import shutil
import signal
import sys
import time
from pathlib import Path

import numpy as np

from protocol.mean_error import PAPER_TABLE_6, format_table
from rig_emulator.config.loader import ConfigError, available, load_config, parse_override
from rig_emulator.compile_notice import compile_notice
from rig_emulator.config.schema import SCHEMA, STRATEGIES
from rig_emulator.controllers.base import PluginError
from rig_emulator.link.serve_args import add_serve_args



def _add_config_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--airframe", default="hilms",
                   help=f"airframe preset (Table 2): {', '.join(available('airframes'))} (default: %(default)s, the "
                        "hardware rig; hilms-ideal is the ideal plant)")
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


TLOG_BYTES_PER_ROW = 700  # about eleven messages a log row


def _parse_start_time(text: str | None) -> float | None:
    """``--start-time``: Unix seconds, or an ISO 8601 date and time (UTC unless it names its offset)."""
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        pass
    try:
        when = datetime.datetime.fromisoformat(text.strip())
    except ValueError:
        raise ConfigError(f"--start-time {text!r}: expected Unix seconds or an ISO 8601 time such as "
                          "2026-11-23T09:00:00Z") from None
    if when.tzinfo is None:
        when = when.replace(tzinfo=datetime.timezone.utc)
    return when.timestamp()


def _series_writer(path: Path, n_rows: int, cfg, start_unix_s: float | None):
    """The writer for ``--out``, after checking that the file's directory exists and has room for
    the run (refused before anything runs)."""
    from rig_emulator.headless.series_files import WRITERS, bytes_per_row

    if path.suffix not in (*WRITERS, ".tlog"):
        raise ConfigError(f"--out {path}: unsupported file type {path.suffix!r}; use .npz, .csv or .tlog")
    if not path.parent.is_dir():
        raise ConfigError(f"--out {path}: directory {str(path.parent)!r} does not exist")
    need = n_rows * (TLOG_BYTES_PER_ROW if path.suffix == ".tlog" else bytes_per_row(path.suffix))
    free = shutil.disk_usage(path.parent).free
    if need > free:
        raise ConfigError(f"--out {path}: the run records {n_rows} rows, about {need / 2**30:.1f} GiB while it is "
                          f"written, and {str(path.parent)!r} has {free / 2**30:.1f} GiB free; shorten --duration or "
                          "lower sim.log_rate_hz (e.g. --set sim.log_rate_hz=10)")
    if path.suffix == ".tlog":
        return None  # exported from the whole run (_simulate_to_tlog)
    return WRITERS[path.suffix](path)


def cmd_simulate(args) -> int:
    overrides = _overrides(args)
    overrides["control.strategy"] = args.strategy
    overrides["sim.seed"] = args.seed
    if args.duration is not None:
        overrides["sim.duration"] = args.duration
    if args.omega is not None:
        overrides["guidance.omega"] = args.omega
    if args.controller:
        overrides["controller.plugin"] = args.controller
    cfg = load_config(airframe=args.airframe, scenario=args.scenario, files=args.config, overrides=overrides)
    _params_need_a_plugin(cfg)
    if args.omega is not None and not (cfg["guidance.type"] == "attitude"
                                       and any(a != 0.0 for a in cfg["guidance.amplitude_deg"])):
        raise ConfigError(f"--omega: scenario {args.scenario!r} flies no harmonic reference (Eq. 44), so --omega would "
                          "change nothing; it applies to 'harmonic' (or guidance.type = 'attitude' with a non-zero "
                          "guidance.amplitude_deg)")
    out = Path(args.out) if args.out else None
    start = _parse_start_time(args.start_time)
    if out is not None and out.suffix == ".tlog":
        return _simulate_to_tlog(args, cfg, out, start)
    return _simulate_streamed(args, cfg, out, start)


def _params_need_a_plugin(cfg) -> None:
    """``controller.params`` set with no plug-in to take them would change nothing: refused."""
    if cfg["controller.params"] and not cfg["controller.plugin"]:
        names = ", ".join(f"controller.params.{n}" for n in cfg["controller.params"])
        raise ConfigError(f"{names}: no controller plug-in flies to take it (name one with --controller MODULE:NAME "
                          "or controller.plugin)")


def _simulate_to_tlog(args, cfg, out: Path, start_unix_s: float | None) -> int:
    """A .tlog is still exported from the whole run held in memory (not streamed yet); its
    records are stamped from ``start_unix_s`` (default: now, whole seconds)."""
    from protocol.run_label import run_label
    from rig_emulator.link.telemetry.tlog_export import export_tlog
    from rig_emulator.simulation.faults import failsafe_cause_text
    from rig_emulator.simulation.run import Simulation

    n_rows = -(-int(round(cfg["sim.duration"] * cfg["sim.physics_rate_hz"]))
               // int(round(cfg["sim.physics_rate_hz"] / cfg["sim.log_rate_hz"])))
    _series_writer(out, n_rows, cfg, start_unix_s)  # the checks: directory, free space
    with compile_notice(cfg=cfg):
        sim = Simulation(cfg)
        sim.warm_up()
    result = sim.run()
    fs = result.series["failsafe"]
    failsafe = None
    if np.any(fs > 0):
        i = int(np.argmax(fs > 0))
        failsafe = (float(result.series["t"][i]), failsafe_cause_text(int(fs[i])))
    _print_summary(args, cfg, result, result.mean_errors(), result.reached_t, failsafe)
    label = run_label(args.scenario, cfg["control.strategy"], cfg["airframe.name"], cfg["sim.seed"])
    export_tlog(result, out, epoch_s=float(int(time.time())) if start_unix_s is None else start_unix_s, label=label)
    return 0


def _simulate_streamed(args, cfg, out: Path | None, start_unix_s: float | None) -> int:
    """Run in chunks (memory bounded whatever the duration), the series streamed to ``--out``;
    Ctrl-C ends the run after the current chunk, keeps what was simulated and exits 130."""
    from rig_emulator.simulation.faults import failsafe_cause_text
    from rig_emulator.headless.streamed import StreamedRun

    with compile_notice(cfg=cfg):
        run = StreamedRun(cfg)
        run.warm_up()
    n_rows = -(-int(round(cfg["sim.duration"] * cfg["sim.physics_rate_hz"])) // run.sim.log_div)
    writer = _series_writer(out, n_rows, cfg, start_unix_s) if out is not None else None
    previous = signal.signal(signal.SIGINT, lambda *_: run.request_stop())
    try:
        result = run.run([writer] if writer is not None else [])
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    finally:
        signal.signal(signal.SIGINT, previous)
    if writer is not None:
        writer.commit()
    if result.interrupted:
        kept = f"; {result.rows} rows written to {out}" if writer is not None else ""
        print(f"rig-emulator: interrupted at t = {result.sim_time_s:.3f} s of {cfg['sim.duration']:g} s{kept}",
              file=sys.stderr, flush=True)
        return 130
    fs = None if result.failsafe is None else (result.failsafe[0], failsafe_cause_text(result.failsafe[1]))
    _print_summary(args, cfg, result, result.mean_errors, result.reached_t, fs)
    return 0


def _print_summary(args, cfg, result, errors: dict, reached, failsafe) -> None:
    """The figures of a finished run: mean errors (Eq. 45), failsafe, waypoints (text or --json)."""
    label = f"{_controller_label(cfg, args.strategy)} ({args.airframe})"
    rows = {label: errors}
    plugin = cfg["controller.plugin"]
    # the paper's Table 6 is its own controllers': next to a plug-in it would read as a grade of it
    paper = PAPER_TABLE_6.get(args.strategy) if args.scenario == "helix" and not plugin else None
    if paper is not None:
        rows[f"paper {args.strategy}"] = paper
    fs = None if failsafe is None else {"t_s": failsafe[0], "cause": failsafe[1], "action": cfg["failsafe.action"]}
    if args.json:
        print(json.dumps({"scenario": args.scenario, "strategy": args.strategy, "seed": args.seed,
                          "controller": cfg["controller.plugin"] or None,
                          "mean_errors": {k: (None if not math.isfinite(v) else v) for k, v in errors.items()},
                          "sim_time_s": result.sim_time_s, "wall_time_s": result.wall_time_s,
                          "real_time_factor": result.real_time_factor, "failsafe": fs}))
        return
    print(f"scenario {args.scenario}, {label}, seed {args.seed}: "
          f"{result.sim_time_s:g} s simulated in {result.wall_time_s:.3f} s ({result.real_time_factor:.0f}x real time)")
    print(f"mean errors (Eq. 45) on the plant {args.airframe!r}"
          + (" (the hardware rig; --airframe hilms-ideal for the ideal plant)" if args.airframe == "hilms" else "")
          + ":")
    print(format_table(rows))
    if paper is not None and result.sim_time_s >= 60.0 - 1e-9:
        near = [c for c in paper if math.isfinite(errors[c]) and 0.5 <= errors[c] / paper[c] <= 2.0]
        print(f"fidelity check of the emulator (the paper's own {args.strategy.upper()} against its Table 6): "
              f"{len(near)} of {len(paper)} mean errors within a factor 2 of the paper's")
    if plugin and args.scenario == "helix":
        print("the paper publishes no numbers for your controller; to compare it with the paper's four controllers "
              f"on the same runs: rig-gcs reproduce -o DIR --controller {plugin} (docs/how-to/compare-controllers.md)")
    if fs is not None:
        what = "motors stopped, disarmed" if fs["action"] == "disarm" else "reported only"
        print(f"loss of control at t = {fs['t_s']:.2f} s ({fs['cause']}): {what} (docs/how-to/faults.md)")
    if cfg["guidance.type"] == "waypoints":
        done = int(np.isfinite(reached).sum())
        times = ", ".join("-" if not np.isfinite(t) else f"{t:.2f}" for t in reached)
        print(f"waypoints reached: {done}/{reached.size} at t = [{times}] s "
              f"(switching radius {cfg['guidance.switching_radius']:g} m)")


def _controller_label(cfg, strategy: str) -> str:
    """Who flew: the strategy, or the plug-in and what of the strategy it kept."""
    plugin = cfg["controller.plugin"]
    if not plugin:
        return f"strategy {strategy}"
    from rig_emulator.controllers import load_controller

    replaces = load_controller(plugin).replaces
    kept = {"both": "", "attitude": f" + position loop of {strategy}", "position": f" + attitude loop of {strategy}"}
    return f"controller {plugin}{kept[replaces]}"


def cmd_serve(args) -> int:
    from rig_emulator.link.serve import cmd_serve as serve

    overrides = _overrides(args)
    if args.strategy is not None:
        overrides["control.strategy"] = args.strategy
    if args.controller:
        overrides["controller.plugin"] = args.controller
    if any(k == "controller.params" or k.startswith("controller.params.") for k in overrides) or args.config:
        try:
            cfg = load_config(airframe=args.airframe, scenario=getattr(args, "scenario", None), files=args.config,
                              overrides=overrides)
        except ConfigError:
            cfg = None  # serve reports a bad configuration its own way
        if cfg is not None:
            _params_need_a_plugin(cfg)
    return serve(args, overrides)


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
    overrides = _overrides(args)
    if args.controller:
        overrides["controller.plugin"] = args.controller
    cfg = load_config(airframe=args.airframe, scenario=args.scenario, files=args.config, overrides=overrides)
    plugin_lines = _plugin_param_lines(cfg)  # loads the plug-in first: a bad one is refused before any listing
    for key, spec in SCHEMA.items():
        unit = f" [{spec.unit}]" if spec.unit else ""
        values = spec.describe_values()
        if key == "airframe.name":
            values = f"{values}: one of " + ", ".join(repr(a) for a in available("airframes"))
        print(f"{key} = {cfg[key]!r}{unit}  ({values})\n    {spec.doc}")
        for name, field in spec.item.items():  # the fields of each entry of a list of tables
            field_unit = f" [{field.unit}]" if field.unit else ""
            print(f"    .{name}{field_unit}: {field.describe_values()}: {field.doc}")
        if key == "controller.params":
            for line in plugin_lines:
                print(line)
    return 0


def _plugin_param_lines(cfg) -> list[str]:
    """The parameters of the config's controller plug-in (``controller.plugin``, or
    ``--controller``) as ``rig-emulator params`` lists the rest: ``controller.params.NAME =
    value [unit]  (allowed values; default ...)`` then its doc and, when served, its MAVLink names."""
    plugin = cfg["controller.plugin"]
    if not plugin:
        return []
    from rig_emulator.controllers import PluginError, load_controller
    from rig_emulator.link.parameters.plugin_params import plugin_params

    ctrl = load_controller(plugin, cfg["controller.params"])
    defaults = load_controller(plugin).params  # what it flies with when the config sets nothing
    cp = ctrl.params
    served: dict[str, list[str]] = {}
    not_served = ""
    try:
        for p in plugin_params(ctrl, 0, set()):
            served.setdefault(p.param, []).append(p.name)
    except PluginError as exc:
        not_served = f"; not servable over MAVLink: {exc.problem}"
    lines = []
    for name in cp.names():
        info = cp.info.get(name, {})
        lo, hi = cp.limits(name)
        unit = str(info.get("unit", ""))
        rng = "any finite number" if math.isinf(lo) and math.isinf(hi) else f"in [{lo:g}, {hi:g}]"
        value, default = getattr(cp, name), getattr(defaults, name)
        if cp._scalar[name]:
            values = rng
        else:
            n = len(value)
            values = f"{n} finite numbers" if rng == "any finite number" else f"{n} numbers, each {rng}"
            value, default = [float(v) for v in value], [float(v) for v in default]
        doc = str(info.get("doc", f"parameter {name!r} of controller {plugin}"))
        names = served.get(name, [])
        if names:
            doc += "; served as " + (names[0] if len(names) == 1 else f"{names[0]}..{names[-1]}")
        doc += not_served
        unit_text = f" [{unit}]" if unit else ""
        lines.append(f"controller.params.{name} = {value!r}{unit_text}  ({values}; default {default!r})\n    {doc}")
    if not lines:
        lines.append(f"    (controller {plugin} declares no parameters)")
    return lines


def cmd_scenarios(args) -> int:
    print("scenarios:", ", ".join(available("scenarios")))
    print("airframes:", ", ".join(available("airframes")))
    print("strategies:", ", ".join(STRATEGIES))
    return 0


def cmd_divergence(args) -> int:
    from rig_emulator.headless.divergence import format_row, run_stats

    overrides = _overrides(args)
    rows = []
    with compile_notice():
        for scenario in args.scenario:
            for seed in args.seed or [0]:
                for airframe in args.airframe or ["hilms", "hilms-ideal"]:
                    stats, threshold, duration = run_stats(scenario, airframe, args.strategy, seed, args.duration,
                                                           overrides, args.threshold, args.at)
                    rows.append((scenario, airframe, seed, stats, threshold, duration))
                    if not args.json:
                        print(format_row(scenario, airframe, seed, stats, threshold), flush=True)
    if args.markdown:
        import shlex

        from protocol.atomic_file import atomic_write_text
        from rig_emulator.headless.divergence import markdown_table

        typed = " ".join(["rig-emulator", *(shlex.quote(a) for a in sys.argv[1:])])
        head = (f"Written by `{typed}`: onboard minus SIM_STATE, strategy "
                f"{args.strategy}, the scenarios' durations.\n\n")
        atomic_write_text(args.markdown, head + markdown_table(rows, tuple(args.at)))
    if args.json:
        print(json.dumps([{"scenario": sc, "airframe": af, "seed": seed, "strategy": args.strategy, "duration_s": dur,
                           "threshold_m": thr, "max_m": st.max_m, "rms_m": st.rms_m,
                           "first_over_s": None if math.isnan(st.first_over_s) else st.first_over_s,
                           "at_ned_m": {f"{t:g}": list(v) for t, v in st.at.items()},
                           "slid_on_ground_m": {"onboard": st.slid_onboard_m, "sim_state": st.slid_physics_m},
                           "sim_state_on_ground_s": st.grounded_physics_s}
                          for sc, af, seed, st, thr, dur in rows]))
    return 0


def cmd_hover_thrust(args) -> int:
    from rig_emulator.headless.hover_thrust import fly_fractions, format_measurement, format_trial, measure_hover_fraction

    overrides = _overrides(args)
    results = []
    with compile_notice():
        for airframe in args.airframe or ["hilms", "hilms-ideal"]:
            if args.thrust:
                trials = fly_fractions(airframe, args.thrust, seed=args.seed, overrides=overrides,
                                       settle_s=args.settle, window_s=args.window)
                results.append({"airframe": airframe, "seed": args.seed, "trials": [t.__dict__ for t in trials]})
                if not args.json:
                    print(f"{airframe} (seed {args.seed}, {args.settle:g} s hold at 2 m, then {args.window:g} s level "
                          "at each thrust):")
                    print("\n".join(format_trial(t, args.window) for t in trials), flush=True)
                continue
            m = measure_hover_fraction(airframe, seed=args.seed, overrides=overrides, settle_s=args.settle,
                                       window_s=args.window)
            results.append(m.as_dict())
            if not args.json:
                print(format_measurement(m), flush=True)
    if args.json:
        print(json.dumps(results))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rig-emulator", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("serve", help="run the rig and serve MAVLink (the default command); keeps parameters and "
                                     "the mission in ./rig-state; optional MAVLink 2 signing (see serve --help)")
    add_serve_args(p)
    _add_config_args(p)
    p.add_argument("--strategy", choices=STRATEGIES, default=None,
                   help="controller strategy (default: the configuration's control.strategy, smc-flc)")
    p.add_argument("--controller", metavar="MODULE:NAME",
                   help="fly a controller plug-in instead of (part of) the strategy; its parameters are served "
                        "under its prefix; a failing plug-in trips the failsafe (docs/how-to/your-controller.md)")
    p.set_defaults(func=cmd_serve)

    p = sub.add_parser("simulate", help="run a scenario headless and print the mean errors")
    p.add_argument("--scenario", required=True, help="scenario preset (see `rig-emulator scenarios`)")
    p.add_argument("--strategy", default="smc-flc", choices=STRATEGIES)
    p.add_argument("--duration", type=float, help="simulated seconds (default: the scenario's)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--omega", type=float, help="harmonic frequency in rad/s (Eq. 44)")
    p.add_argument("--controller", metavar="MODULE:NAME",
                   help="fly a controller plug-in instead of (part of) the strategy (docs/how-to/your-controller.md)")
    p.add_argument("--out", help="write the time series (.npz, .csv, or .tlog: the MAVLink messages the live rig streams); "
                                 ".npz and .csv are streamed as the run goes (memory does not grow with --duration)")
    p.add_argument("--start-time", metavar="WHEN",
                   help="a .tlog's start (its record time stamps): Unix seconds or ISO 8601 (default: now, whole "
                        "seconds). Message time stamps count simulated time from 0 whatever it is; the same "
                        "arguments with the same --start-time give the same bytes")
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
    p.add_argument("--controller", metavar="MODULE:NAME",
                   help="also list this controller plug-in's own parameters (controller.params.NAME, with their "
                        "ranges and defaults); without it, those of the config's controller.plugin, if any")
    _add_config_args(p)
    p.set_defaults(func=cmd_params)

    p = sub.add_parser("divergence", help="how far the onboard position and the physics vehicle (SIM_STATE) part "
                                          "over a scenario, on both plants (docs/explanation/sim-state.md)")
    p.add_argument("--scenario", action="append", required=True, help="scenario preset (repeatable)")
    p.add_argument("--seed", type=int, action="append", help="seed (repeatable; default 0)")
    p.add_argument("--strategy", default="smc-flc", choices=STRATEGIES)
    p.add_argument("--duration", type=float, help="simulated seconds (default: the scenario's)")
    p.add_argument("--airframe", action="append", help="plant (repeatable; default: hilms and hilms-ideal)")
    p.add_argument("--threshold", type=float, help="report the first time they part by more than this (m; default "
                                                   "estimation.divergence_warning_m)")
    p.add_argument("--at", type=float, nargs="*", default=[30.0, 60.0], metavar="S",
                   help="times (s) at which to print the vector (default: 30 60)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--markdown", metavar="FILE", help="also write the figures as a documentation page (a table)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override one parameter")
    p.set_defaults(func=cmd_divergence)

    p = sub.add_parser("hover-thrust", help="measure the normalised collective thrust (SET_ATTITUDE_TARGET.thrust) "
                                            "that hovers, per plant (docs/how-to/attitude-thrust.md)")
    p.add_argument("--airframe", action="append", help="plant (repeatable; default: hilms and hilms-ideal)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--settle", type=float, default=20.0, help="seconds of position hold at 2 m before the "
                                                             "thrust is applied (default %(default)s)")
    p.add_argument("--window", type=float, default=5.0, help="seconds flown at each thrust (default %(default)s)")
    p.add_argument("--thrust", type=float, nargs="+", metavar="F",
                   help="fly these thrusts (0..1) and print the climb of each, instead of searching the hover")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override one parameter")
    p.set_defaults(func=cmd_hover_thrust)

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
    except (ConfigError, PluginError) as exc:
        print(f"rig-emulator: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C before a command installed its own handling (e.g. while compiling)
        print("rig-emulator: interrupted", file=sys.stderr, flush=True)
        return 130
    except BrokenPipeError:  # `rig-emulator params | head`: the reader left; stop without a traceback
        from protocol.closed_pipe import quiet_exit_on_closed_pipe

        return quiet_exit_on_closed_pipe()


if __name__ == "__main__":
    sys.exit(main())
