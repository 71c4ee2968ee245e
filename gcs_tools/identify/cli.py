"""``rig-gcs identify``: fit the emulated rig's parameters to the paper's numbers or to flight logs.

Registered in :mod:`gcs_tools.cli` by :func:`add_parser`. Exit codes: 0 preset written, 1 a run
failed (a simulation, the Dask cluster), 2 bad input (an unknown key, a bound outside the key's
range, an unreadable or unsuitable log, bad options), reported before anything runs.
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import tomllib
from datetime import datetime, timezone
from pathlib import Path

from gcs_tools.arg_types import finite_number, whole_number_at_least
from gcs_tools.errors import EXIT_OK, OperationError, UsageError

_workers = whole_number_at_least(1)
_seed = whole_number_at_least(0)
_evals = whole_number_at_least(1)
_starts = whole_number_at_least(0)


def _fraction(text: str) -> float:
    v = finite_number(text)
    if not 0.0 < v < 0.5:
        raise argparse.ArgumentTypeError(f"{text!r}: must be in (0, 0.5)")
    return v


def _positive(text: str) -> float:
    v = finite_number(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be > 0")
    return v


def add_parser(sub) -> None:
    p = sub.add_parser(
        "identify", help="fit parameters of the emulated rig to the paper's numbers or to flight logs",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Fits chosen configuration parameters, within bounds and optional Gaussian priors, to targets: "
                    "the paper's 18 published numbers (--paper: Table 4, Table 6, Fig. 19) or your own flight logs "
                    "(--tlog FILE --scenario NAME: simulated ATTITUDE, LOCAL_POSITION_NED and load cells against "
                    "the logged ones). Every evaluation is a set of headless runs on local processes or a Dask "
                    "cluster and is appended to --record, so rerunning the same command resumes without "
                    "re-simulating. Writes the fitted values as a TOML preset for --config. See docs/how-to/identify.md.",
        epilog="examples:\n"
               "  rig-gcs identify --paper --params motors.time_constant=0.02:0.1,airframe.ixx=0.04:0.09 "
               "-o fit.toml --record fit.jsonl\n"
               "  rig-gcs identify --tlog run.tlog --scenario helix --strategy smc-flc "
               "--params smc.k[0]=0.5:3 -o twin.toml\n"
               "  rig-gcs identify --tlog sysid.tlog -o my-rig.toml      (regression on an identification flight)")
    g = p.add_argument_group("parameters")
    g.add_argument("--params", action="append", default=[], metavar="KEY=LO:HI[:START],...",
                   help="parameters to fit and their bounds; KEY as for --set, or one element KEY[i] of a list key, "
                        "KEY[i].FIELD of a list of tables, a leaf of a sensor-model tree (repeatable)")
    g.add_argument("--spec", metavar="FILE.toml", help="a fit spec: [[param]] tables (key, lo, hi, start, prior) and "
                                                     "optionally [[tlog]] tables (path, scenario, strategy, ...)")
    g.add_argument("--prior", action="append", default=[], metavar="KEY=MEAN+-SIGMA",
                   help="Gaussian prior on a fitted parameter (repeatable)")
    g.add_argument("--step", action="append", default=[], metavar="KEY=STEP",
                   help="smallest finite-difference step of a parameter in its unit, for a key the rig quantises "
                        "(e.g. control.actuation_delay=0.001: whole physics steps) (repeatable)")
    g = p.add_argument_group("targets (one of)")
    g.add_argument("--paper", action="store_true", help="the paper's 18 numbers (gcs_tools/identify/paper_targets.toml)")
    g.add_argument("--claims", action="store_true", help="with --paper: also the paper's qualitative claims the same "
                                                         "runs test, as hinge residuals")
    g.add_argument("--paper-variant", choices=("full", "short"), default="full",
                   help="full: Table 4 over the reproduction's 13 frequencies; short: 7 of them (default %(default)s)")
    g.add_argument("--paper-targets", metavar="PATTERNS",
                   help="with --paper: fit only the numbers whose name matches one of these comma-separated shell "
                        "patterns (e.g. 'table6.*.z_m,fig19.*'), or a group: position (Table 6 X/Y/Z, Fig. 19), "
                        "attitude (Table 4, Table 6 angles); default all 18")
    g.add_argument("--paper-seeds", type=_evals, default=1, metavar="N",
                   help="with --paper: every number the mean over the runs of N seeds (--seed .. --seed + N - 1): "
                        "%(default)s")
    g.add_argument("--no-paper-priors", action="store_true",
                   help="with --paper: leave out the paper's physical priors (gcs_tools/identify/paper_priors.toml: "
                        "joint.coulomb 0 +- 0.01 N m, the joint being 'fully lubricated'; motors.thrust_bias_grf "
                        "0 +- 10 gr.F, Eq. 40 being calibrated on the same load cells), otherwise applied to any "
                        "fitted element of those keys without its own --prior")
    g.add_argument("--held-out", choices=("logo", "single"), metavar="SPLITS",
                   help="with --paper: instead of one fit, fit on groups of the paper's numbers (Table 4, Table 6, "
                        "Fig. 19) and predict the others: logo = fit on two groups, predict the third; single = fit "
                        "on one, predict two; plus a fit on all three. -o FILE.json gets the table (and FILE.md its "
                        "markdown); every key starts mid-range (docs/explanation/paper-fit.md)")
    g.add_argument("--tlog", action="append", default=[], metavar="FILE", help="a flight log to fit (repeatable)")
    g = p.add_argument_group("flight logs")
    g.add_argument("--method", choices=("auto", "regression", "simulation"), default="auto",
                   help="regression: every effect from an identification flight's log (scenario sysid) by "
                        "regression, with 95 %% intervals and a model check, nothing simulated; simulation: the "
                        "scenario re-simulated and --params fitted; auto (default): regression for --tlog without "
                        "--params / --spec")
    g.add_argument("--hold", action="append", default=[], metavar="EFFECT",
                   help="regression: keep an effect at the base configuration's value (repeatable): thrust_gain, "
                        "thrust_bias, curve, delay, inertia, viscous, coulomb, cog")
    g.add_argument("--calibration-study", type=_evals, metavar="N",
                   help="run the regression's calibration study: N random hidden draws (sysid flights on hilms), "
                        "coverage of the 95 %% intervals and median errors, matched and mismatched")
    g.add_argument("--study-seed", type=int, default=0, metavar="S",
                   help="calibration study: 0 (default) the draws and noise seeds the intervals' scales were "
                        "measured on; another value draws other hidden values and flies other seeds")
    g.add_argument("--scenario", action="append", default=[], metavar="NAME",
                   help="the scenario preset flown in the log (once for all logs, or once per --tlog in order)")
    g.add_argument("--strategy", action="append", default=[], help="the strategy flown (once, or once per --tlog; "
                                                                  "default smc-flc)")
    g.add_argument("--duration", type=_positive, help="simulated seconds (default: up to the last logged sample used)")
    g.add_argument("--t-offset", type=finite_number, default=0.0, metavar="S",
                   help="log time (s of time_boot_ms) of the scenario's t = 0: %(default)s")
    g.add_argument("--from", dest="t_from", type=finite_number, metavar="S", help="fit from this scenario time (s)")
    g.add_argument("--to", dest="t_to", type=finite_number, metavar="S", help="fit up to this scenario time (s)")
    g.add_argument("--channels", default="attitude,position,load_cells",
                   help="series compared: attitude, position, load_cells (default: %(default)s)")
    g.add_argument("--scale", action="append", default=[], metavar="CHANNEL=VALUE",
                   help="residual scale of a channel (deg, m, N; default attitude=1, position=0.05, load_cells=0.1)")
    g.add_argument("--fit-hz", type=_positive, default=10.0, help="logged samples used per second: %(default)s")
    g.add_argument("--sysid", type=int, help="vehicle system id in the logs (default: the first)")
    g = p.add_argument_group("base configuration")
    g.add_argument("--airframe", default="hilms", help="airframe preset: %(default)s")
    g.add_argument("--config", action="append", default=[], metavar="FILE", help="extra TOML parameter file (repeatable)")
    g.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override one parameter (repeatable)")
    g = p.add_argument_group("running")
    g.add_argument("-o", "--output", metavar="FILE.toml", help="the fitted preset to write (needed by the "
                                                                "simulation method)")
    g.add_argument("--record", metavar="FILE.jsonl", help="record of every evaluation; rerunning with it resumes")
    g.add_argument("--json", metavar="FILE.json", help="also write the full result (values, sigmas, residuals) as JSON")
    g.add_argument("--workers", type=_workers, help="local processes (default: one per core; 1 = in this process)")
    g.add_argument("--scheduler", metavar="ADDR", help="run the simulations on a Dask cluster, e.g. tcp://HOST:8786")
    g.add_argument("--max-evals", type=_evals, metavar="N", help="stop after N parameter points (the best is written)")
    g.add_argument("--seed", type=_seed, default=0, help="seed of every simulated run: %(default)s")
    g.add_argument("--starts", type=_starts, default=0, metavar="N",
                   help="evaluate N scrambled Halton points of the bounds first and start from the best: %(default)s")
    g.add_argument("--fd-step", type=_fraction, help="finite-difference step, fraction of each range (default 0.08 "
                                                      "with --paper, whose runs are not smooth at smaller steps; 0.02 "
                                                      "with --tlog)")
    g.add_argument("--tol", type=_positive, default=1e-3, help="least_squares ftol/xtol/gtol: %(default)s")
    g.add_argument("--no-progress", action="store_true", help="no progress output on stderr")
    p.set_defaults(func=cmd_identify)


def _read_spec(path: str) -> dict:
    p = Path(path)
    try:
        return tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"--spec {p}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"--spec {p}: cannot read ({exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise UsageError(f"--spec {p}: not valid TOML ({exc})") from None


def _per_log(values: list, n: int, name: str, default):
    if not values:
        return [default] * n
    if len(values) == 1:
        return values * n
    if len(values) != n:
        raise UsageError(f"--{name}: give it once for every log or once per --tlog ({n}), not {len(values)} times")
    return values


def _logs(args, spec: dict, spec_path):
    from gcs_tools.identify.tlog_target import FlightLog

    logs = []
    n = len(args.tlog)
    if n:
        scen = _per_log(args.scenario, n, "scenario", None)
        if None in scen:
            raise UsageError("--tlog needs the scenario that was flown: --scenario NAME")
        strat = _per_log(args.strategy, n, "strategy", "smc-flc")
        for path, sc, st in zip(args.tlog, scen, strat):
            logs.append(FlightLog(path, sc, st, args.duration, args.t_offset, args.t_from, args.t_to, args.sysid))
    items = spec.get("tlog", [])
    if not isinstance(items, list) or not all(isinstance(t, dict) for t in items):
        raise UsageError(f"--spec {spec_path}: 'tlog' must be a list of tables ([[tlog]])")
    allowed = {"path", "scenario", "strategy", "duration", "t_offset", "from", "to", "sysid"}
    for i, t in enumerate(items):
        unknown = set(t) - allowed
        if unknown:
            raise UsageError(f"--spec {spec_path}: tlog[{i}]: unknown field(s) {sorted(unknown)}; allowed: "
                             f"{', '.join(sorted(allowed))}")
        if "path" not in t or "scenario" not in t:
            raise UsageError(f"--spec {spec_path}: tlog[{i}]: needs path and scenario")
        path = Path(t["path"])
        if not path.is_absolute():
            path = Path(spec_path).resolve().parent / path
        logs.append(FlightLog(str(path), str(t["scenario"]), str(t.get("strategy", "smc-flc")), t.get("duration"),
                              float(t.get("t_offset", 0.0)), t.get("from"), t.get("to"), t.get("sysid")))
    return logs


def _scales(items: list) -> dict:
    out = {}
    for text in items:
        if "=" not in text:
            raise UsageError(f"--scale {text!r}: expected CHANNEL=VALUE")
        k, v = (s.strip() for s in text.split("=", 1))
        try:
            out[k] = float(v)
        except ValueError:
            raise UsageError(f"--scale {text!r}: {v!r} is not a number") from None
    return out


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("hilms-sil")
    except Exception:  # noqa: BLE001 - not installed as a distribution
        return "unknown"


def build(args):
    """(problem, params, base) from the arguments; UsageError for anything wrong with them."""
    from gcs_tools.identify import params as P
    from gcs_tools.identify.problem import Base
    from rig_emulator.config.loader import ConfigError, available, load_config, parse_override

    if args.workers is not None and args.scheduler:
        raise UsageError("give --workers (local processes) or --scheduler (a Dask cluster), not both")
    try:
        spec = _read_spec(args.spec) if args.spec else {}
        unknown = set(spec) - {"param", "tlog"}
        if unknown:
            raise UsageError(f"--spec {args.spec}: unknown table(s) {sorted(unknown)}; allowed: param, tlog")
        params = []
        for text in args.params:
            params += P.parse_params_arg(text)
        if spec:
            params += P.params_from_spec(spec, f"--spec {args.spec}")
        priors = dict(P.parse_prior_arg(t) for t in args.prior)
        params = P.merge(params, priors, dict(P.parse_step_arg(t) for t in args.step))
        if not params:
            raise UsageError("no parameter to fit: give --params KEY=LO:HI or --spec FILE with [[param]] tables")
        if args.airframe not in available("airframes"):
            raise UsageError(f"--airframe {args.airframe!r}: choose one of {', '.join(available('airframes'))}")
        base = Base(args.airframe, tuple(args.config), tuple(parse_override(s) for s in args.set))
        load_config(airframe=args.airframe, files=args.config, overrides=dict(base.overrides))  # bad base: exit 2
        logs = _logs(args, spec, args.spec)
        if args.paper and logs:
            raise UsageError("give --paper or flight logs (--tlog), not both")
        if args.claims and not args.paper:
            raise UsageError("--claims goes with --paper")
        if (args.paper_targets is not None or args.paper_seeds != 1) and not args.paper:
            raise UsageError("--paper-targets and --paper-seeds go with --paper")
        no_priors, held = getattr(args, "no_paper_priors", False), getattr(args, "held_out", None)
        if (no_priors or held) and not args.paper:
            raise UsageError("--no-paper-priors and --held-out go with --paper")
        if held and (args.paper_targets is not None or args.claims):
            raise UsageError("--held-out chooses the numbers of each fit itself: drop --paper-targets and --claims")
        args.paper_priors_used = []
        if args.paper and not no_priors:
            from gcs_tools.identify import paper_priors

            params, args.paper_priors_used = paper_priors.apply(params, explicit=set(priors))
        if args.paper:
            from gcs_tools.identify.paper import PaperProblem

            try:
                problem = PaperProblem(base, seed=args.seed, claims=args.claims, variant=args.paper_variant,
                                       seeds=args.paper_seeds, targets=args.paper_targets)
            except ValueError as exc:
                raise UsageError(f"--paper-targets: {exc}") from None
        elif logs:
            from gcs_tools.identify.tlog_target import TlogProblem

            for lg in logs:
                if lg.scenario not in available("scenarios"):
                    raise UsageError(f"--scenario {lg.scenario!r}: choose one of {', '.join(available('scenarios'))}")
            channels = [c.strip() for c in args.channels.split(",") if c.strip()]
            problem = TlogProblem(logs, base, seed=args.seed, channels=channels, scales=_scales(args.scale),
                                  fit_hz=args.fit_hz)
        else:
            raise UsageError("no targets: give --paper or --tlog FILE --scenario NAME")
        # every job of the start point validated now (a key that does not apply to a scenario, ...)
        for job in problem.jobs(params, P.start_values(params, problem.configs()[0])):
            job.check()
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    return problem, params, base


def _base_text(base) -> str:
    parts = [f"--airframe {base.airframe}"] + [f"--config {f}" for f in base.files]
    parts += [f"--set {k}={json.dumps(v) if isinstance(v, str) else v}" for k, v in base.overrides]
    return " ".join(parts)


def _targets_text(problem) -> str:
    if problem.kind == "paper":
        seeds = (f"seeds {problem.seed}-{problem.seed + problem.seeds - 1} (mean)" if problem.seeds > 1
                 else f"seed {problem.seed}")
        picked = f" selected by {problem.selection!r}" if problem.selection is not None else ""
        t = (f"the paper's {len(problem.targets)} numbers{picked} (gcs_tools/identify/paper_targets.toml), "
             f"{seeds}, variant {problem.variant}")
        return t + (", with its claims" if problem.with_claims else "")
    return "flight logs " + ", ".join(f"{s.log.path} (scenario {s.log.scenario}, {s.log.strategy}; "
                                      f"{', '.join(problem.channels)})" for s in problem.logs) + f", seed {problem.seed}"


def _method(args) -> str:
    if args.method != "auto":
        return args.method
    return "regression" if args.tlog and not args.params and not args.spec and not args.paper else "simulation"


def cmd_identify_regression(args) -> int:
    """``--method regression``: one identification log, every effect with its 95 % interval."""
    from gcs_tools.identify.regression import identify_log, preset_text, report_lines
    from protocol.atomic_file import atomic_write_text
    from rig_emulator.config.loader import ConfigError, load_config, parse_override

    if len(args.tlog) != 1:
        raise UsageError("--method regression fits one log (--tlog FILE) at a time")
    if args.params or args.spec or args.paper:
        raise UsageError("--method regression estimates every effect itself: no --params, --spec or --paper")
    try:
        overrides = dict(parse_override(x) for x in args.set)
        cfg = load_config(airframe=args.airframe, files=args.config, overrides=overrides)
        result = identify_log(args.tlog[0], cfg, hold=tuple(args.hold), t_from=args.t_from, t_to=args.t_to)
    except (ConfigError, ValueError) as exc:
        raise UsageError(str(exc)) from None
    for line in report_lines(result):
        print(line)
    if args.output:
        out = Path(args.output)
        argv = getattr(args, "argv", None)
        command = "rig-gcs " + shlex.join(argv if argv is not None else sys.argv[1:])
        header = [f"fitted by: {command}", f"log: {args.tlog[0]}",
                  "model check: " + ("explains the log" if result.explained else
                                     "DOES NOT explain the log: " + "; ".join(f.text() for f in result.findings))]
        atomic_write_text(out, preset_text(result, header))
        load_config(airframe=args.airframe, files=[*args.config, str(out)], overrides=overrides)  # it loads
        print(f"wrote {out}")
    if args.json:
        doc = {"log": args.tlog[0], "explained": result.explained, "wall_s": result.wall_s,
               "estimates": [e.__dict__ for e in result.estimates], "findings": [f.__dict__ for f in result.findings],
               "worst": result.worst, "whiteness": result.whiteness}
        atomic_write_text(args.json, json.dumps(doc, indent=1, default=float) + "\n")
    return EXIT_OK


def cmd_identify(args) -> int:
    if args.calibration_study:
        from gcs_tools.identify.study import cmd_study

        return cmd_study(args)
    if _method(args) == "regression":
        return cmd_identify_regression(args)
    if not args.output:
        raise UsageError("-o FILE.toml: the fitted preset to write")
    return _cmd_identify_simulation(args)


def _cmd_identify_simulation(args) -> int:
    from gcs_tools.identify.fit import DEFAULT_FD_STEP, PAPER_FD_STEP, identify
    from gcs_tools.identify.preset import header_lines, preset_text
    from protocol.atomic_file import atomic_write_text
    from rig_emulator.config.loader import ConfigError, load_config
    from rig_emulator.sweep import JobFailed, shutdown_pool

    problem, params, base = build(args)
    for name, pp in getattr(args, "paper_priors_used", []):
        print(f"prior {name} = {pp.mean:g} +- {pp.sigma:g} (the paper: {pp.where}; "
              "--no-paper-priors leaves it out)")
    out = Path(args.output)
    if out.exists() and out.is_dir():
        raise UsageError(f"-o {out}: is a directory")
    if not out.parent.exists():
        raise UsageError(f"-o {out}: the directory {out.parent} does not exist")
    if args.record and Path(args.record).resolve() == out.resolve():
        raise UsageError("--record and -o must be different files")
    if getattr(args, "held_out", None):
        if out.suffix == ".md":
            raise UsageError("-o with --held-out: the JSON file (its markdown goes next to it as .md)")
        return _held_out(args, params, base, out)
    try:
        result = identify(problem, params, record_path=args.record, workers=args.workers, scheduler=args.scheduler,
                          max_evals=args.max_evals, starts=args.starts, design_seed=args.seed,
                          fd_step=args.fd_step or (PAPER_FD_STEP if problem.kind == "paper" else DEFAULT_FD_STEP),
                          tol=args.tol, show_progress=not args.no_progress)
    except (JobFailed, ConfigError) as exc:
        raise OperationError(str(exc)) from None
    except OSError as exc:  # e.g. a Dask scheduler that cannot be reached
        raise OperationError(f"running the simulations failed: {exc}") from None
    except RuntimeError as exc:  # dask.distributed missing for --scheduler
        raise OperationError(str(exc)) from None
    finally:
        shutdown_pool()
    argv = getattr(args, "argv", None)
    command = "rig-gcs " + shlex.join(argv if argv is not None else sys.argv[1:])
    date = datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")
    header = header_lines(result, command, date, _version(), _targets_text(problem), _base_text(base))
    base_cfg = load_config(airframe=base.airframe, files=base.files, overrides=dict(base.overrides))
    text = preset_text(result, base_cfg, header)
    atomic_write_text(out, text)
    load_config(airframe=base.airframe, files=[*base.files, out], overrides=dict(base.overrides))  # it loads
    for line in header[7:]:
        print(line)
    for note in result.notes:
        print(f"note: {note}")
    print(f"wrote {out} ({result.evaluations} points, {result.simulated} simulated now, {result.runs} headless "
          f"runs, {result.wall_s:.1f} s wall)")
    if args.json:
        atomic_write_text(args.json, json.dumps(result_document(result, command, date), indent=1,
                                                default=_json_default) + "\n")
    return EXIT_OK


def _held_out(args, params, base, out: Path) -> int:
    from gcs_tools.identify import held_out
    from gcs_tools.identify.fit import PAPER_FD_STEP
    from protocol.atomic_file import atomic_write_text
    from rig_emulator.config.loader import ConfigError
    from rig_emulator.sweep import JobFailed, shutdown_pool

    if args.scheduler:
        raise UsageError("--held-out runs on local processes: drop --scheduler")
    if args.record or args.json:
        raise UsageError("--held-out writes its table to -o FILE.json and keeps its evaluations in memory: "
                         "drop --record and --json")
    argv = getattr(args, "argv", None)
    command = "rig-gcs " + shlex.join(argv if argv is not None else sys.argv[1:])
    try:
        doc = held_out.run(base, params, mode=args.held_out, seed=args.seed, seeds=args.paper_seeds,
                           variant=args.paper_variant, starts=args.starts, max_evals=args.max_evals,
                           fd_step=args.fd_step or PAPER_FD_STEP, tol=args.tol, workers=args.workers,
                           show_progress=not args.no_progress)
    except (JobFailed, ConfigError) as exc:
        raise OperationError(str(exc)) from None
    finally:
        shutdown_pool()
    doc["command"] = command
    text = held_out.markdown(doc, command)
    atomic_write_text(out, json.dumps(_finite(doc), indent=1, sort_keys=True) + "\n")
    md = out.with_suffix(".md")
    atomic_write_text(md, text + "\n")
    print(text)
    print(f"wrote {out} and {md} ({doc['evaluated_points']} points evaluated)")
    return EXIT_OK


def _json_default(x):
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(type(x).__name__)


def _finite(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def result_document(result, command: str, date: str) -> dict:
    corr = result.correlation.tolist() if result.correlation is not None else None
    return _finite({
        "command": command, "date": date, "status": result.status,
        "params": [{"key": p.name, "value": v, "sigma": s, "at_bound": b, "lo": p.lo, "hi": p.hi, "start": st,
                    "prior": list(p.prior) if p.prior else None}
                   for p, v, s, b, st in zip(result.params, result.values, result.sigma, result.at_bound, result.start)],
        "correlation": corr, "cost": result.cost, "residuals": [float(r) for r in result.residuals],
        "prior_residuals": [float(r) for r in result.prior_residuals], "metrics": result.metrics,
        "summary": result.summary, "evaluations": result.evaluations, "simulated": result.simulated,
        "runs": result.runs, "wall_s": result.wall_s, "record": result.record, "notes": result.notes})
