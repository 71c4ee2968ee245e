"""Write the generated parts of the documentation site into docs/generated/.

Each file is made from the code that defines what it describes, so the reference cannot
drift from the product: the command-line help from the argparse parsers of ``rig-emulator``
and ``rig-gcs``, every parameter from the schema (rig_emulator/config/schema.py), its values
on the shipped airframes and its MAVLink name (rig_emulator/link/parameters/table.py), the
telemetry streams from their table (rig_emulator/link/telemetry/stream_table.py) and the
rig's own messages and commands from the dialect (protocol/dialect/hilms.xml). The pages
under docs/ include these files with ``--8<--`` (pymdownx.snippets).

Usage (scripts/docs.sh runs it)::

    python scripts/docs_gen.py            # (re)write docs/generated/
    python scripts/docs_gen.py --check    # exit 1, naming the files, when a committed one differs

The expensive pages are written from a run's output, each saying the command and the machine:
``--benchmarks FILE.json``, ``--reproduce DIR``, ``--compare DIR`` (``rig-gcs reproduce --controller``),
``--held-out FILE.json`` (``rig-gcs identify --paper --held-out``), ``--refit FILE.json``
(``rig-gcs identify --paper --json``), ``--identify-study FILE.json``,
``--stability``; the studies write theirs themselves (``python -m gcs_tools.studies NAME --markdown FILE``).
"""

from __future__ import annotations

import argparse
import importlib
import io
import json
import math
import os
import re
import sys
import textwrap
import xml.etree.ElementTree as ET
from contextlib import redirect_stdout
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "generated"
HELP_WIDTH = "80"  # argparse wraps at $COLUMNS: fixed, so the pages do not depend on the terminal

sys.path.insert(0, str(ROOT))


# --- command-line help ---------------------------------------------------------------------------

def _subparsers(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    return None


def _cli_page(parser: argparse.ArgumentParser, intro: str) -> str:
    out = [intro, ""]

    def walk(p: argparse.ArgumentParser, level: int) -> None:
        out.append(f"{'#' * level} `{p.prog}`")
        out.append("")
        out.append("```text")
        out.append(p.format_help().rstrip())
        out.append("```")
        out.append("")
        sub = _subparsers(p)
        if sub is not None:
            for child in dict.fromkeys(sub.choices.values()):  # aliases point at the same parser
                walk(child, min(level + 1, 4))

    walk(parser, 2)
    return "\n".join(out).rstrip() + "\n"


def cli_pages() -> dict[str, str]:
    os.environ["COLUMNS"] = HELP_WIDTH
    from gcs_tools.cli import build_parser as gcs_parser
    from gcs_tools.studies import STUDIES
    from rig_emulator.cli import build_parser as rig_parser

    studies = ["Generated from `gcs_tools/studies/` (`python -m gcs_tools.studies`, `python -m gcs_tools.studies "
               "NAME --help`). Each study prints its tables; `--markdown FILE` also writes them as a page with the "
               "command, its wall time and the machine (the documentation includes those pages from "
               "`docs/generated/study-*.md`).", "", "| study | what it measures |", "| --- | --- |"]
    studies += [f"| `{name}` | {_cell(what)} |" for name, (_, what) in STUDIES.items()]
    studies.append("")
    for name, (module, _) in STUDIES.items():
        parser = importlib.import_module(f"gcs_tools.studies.{module}").parser()
        studies += [f"### `{parser.prog}`", "", "```text", parser.format_help().rstrip(), "```", ""]
    return {
        "cli-studies.md": "\n".join(studies).rstrip() + "\n",
        "cli-rig-emulator.md": _cli_page(
            rig_parser(), "Generated from `rig_emulator/cli.py`'s parser (`rig-emulator --help`, "
                          "`rig-emulator COMMAND --help`). `rig-emulator` with no command is `rig-emulator serve`."),
        "cli-rig-gcs.md": _cli_page(
            gcs_parser(), "Generated from `gcs_tools/cli.py`'s parser (`rig-gcs --help`, `rig-gcs COMMAND --help`)."),
    }


# --- parameters ----------------------------------------------------------------------------------

def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _value(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        if v and isinstance(v[0], dict):
            return f"{len(v)} entries"
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{}" if not v else f"{len(v)} keys"
    if isinstance(v, str):
        return f'"{v}"' if v else '""'
    return repr(v).lower() if isinstance(v, bool) else repr(v)


def _name(text: str) -> str:
    """A key or MAVLink name as inline code that a narrow table column breaks only after a dot or an
    underscore (the stylesheet stops breaks inside words)."""
    import html

    return "<code>" + html.escape(text).replace(".", ".<wbr>").replace("_", "_<wbr>") + "</code>"


def parameters_page() -> str:
    from rig_emulator.config.loader import load_config
    from rig_emulator.config.schema import SCHEMA
    from rig_emulator.link.parameters.table import EXCLUDED, build_table

    hw = load_config(airframe="hilms")
    ideal = load_config(airframe="hilms-ideal")
    names: dict[str, list[str]] = {}
    for p in build_table():
        names.setdefault(p.key, []).append(p.name)

    sections: dict[str, list[str]] = {}
    for key, spec in SCHEMA.items():
        section = key.split(".")[0]
        mav = names.get(key, [])
        if len(mav) > 3:
            mav_text = f"{_name(mav[0])} .. {_name(mav[-1])}"
        elif mav:
            mav_text = ", ".join(_name(n) for n in mav)
        else:
            mav_text = "not served" if key in EXCLUDED else "-"
        default = _value(hw[key])
        other = _value(ideal[key])
        default_text = f"`{default}`" if default == other else f"`{default}` (hilms-ideal: `{other}`)"
        doc = spec.doc
        if spec.item:
            doc += " Fields: " + "; ".join(
                f"`{name}`{f' [{f.unit}]' if f.unit else ''}: {f.describe_values()}: {f.doc}"
                for name, f in spec.item.items())
        sections.setdefault(section, []).append(
            f"| {_name(key)} | {_cell(spec.unit) or '-'} | {_cell(spec.describe_values())} | {_cell(default_text)} "
            f"| {mav_text} | {_cell(doc)} |")
    out = [
        "Generated from `rig_emulator/config/schema.py` (key, unit, allowed values, description), the "
        "presets of the airframes `hilms` (the default) and `hilms-ideal` (defaults; the ideal plant's "
        "value is shown where it differs) and `rig_emulator/link/parameters/table.py` (the MAVLink "
        "name; a list key is one MAVLink parameter per element). `rig-emulator params` lists the same "
        "with the values of any configuration; `rig-gcs param list CONNECTION` a running rig's.",
        "",
    ]
    for section, rows in sections.items():
        out += [f"### `{section}`", "",
                "| key | unit | allowed values | default | MAVLink | description |",
                "| --- | --- | --- | --- | --- | --- |", *rows, ""]
    return "\n".join(out).rstrip() + "\n"


# --- MAVLink -------------------------------------------------------------------------------------

def streams_page() -> str:
    from protocol.dialect import mavlink as M
    from rig_emulator.link.telemetry.stream_table import ON_REQUEST, STREAMS

    groups = {getattr(M, n): n[len("MAV_DATA_STREAM_"):] for n in dir(M)
              if n.startswith("MAV_DATA_STREAM_") and n != "MAV_DATA_STREAM_ENUM_END"}
    rows = [f"| {s.name} | {s.msg_id} | {s.default_hz:g} | {groups.get(s.group, s.group)} |"
            for s in sorted(STREAMS.values(), key=lambda s: (-s.default_hz, s.name))]
    total = sum(s.default_hz for s in STREAMS.values())
    extra = sorted(M.mavlink_map[i].msgname for i in ON_REQUEST if i not in STREAMS)
    return "\n".join([
        "Generated from `rig_emulator/link/telemetry/stream_table.py`. Rates are per second of simulated "
        "time and per peer; `MAV_CMD_SET_MESSAGE_INTERVAL` changes one message for the asking peer, "
        "`REQUEST_DATA_STREAM` a whole group. HEARTBEAT (not in the table) goes out at 1 Hz of wall-clock time.",
        "",
        "| message | id | default rate (Hz) | REQUEST_DATA_STREAM group |",
        "| --- | --- | --- | --- |",
        *rows,
        "",
        f"In all {total:g} messages per simulated second at the default rates, plus HEARTBEAT.",
        "",
        "Sent once on `MAV_CMD_REQUEST_MESSAGE` besides the streams above: "
        + ", ".join(extra) + ".",
    ]) + "\n"


def _text(el) -> str:
    return " ".join((el.text or "").split()) if el is not None else ""


def dialect_page() -> str:
    root = ET.parse(ROOT / "protocol" / "dialect" / "hilms.xml").getroot()
    out = ["Generated from `protocol/dialect/hilms.xml` (its own definitions; it includes "
           "`development.xml`, hence `common.xml`, and `component_metadata.xml`).", ""]
    out += ["### Messages", ""]
    for msg in root.iter("message"):
        out += [f"#### {msg.get('name')} ({msg.get('id')})", "", _text(msg.find("description")), "",
                "| field | type | unit | description |", "| --- | --- | --- | --- |"]
        for f in msg.findall("field"):
            enum = f" (`{f.get('enum')}`)" if f.get("enum") else ""
            out.append(f"| `{f.get('name')}` | {f.get('type')} | {f.get('units') or '-'} "
                       f"| {_cell(_text(f))}{enum} |")
        out.append("")
    out += ["### Commands", ""]
    for enum in root.iter("enum"):
        if enum.get("name") != "MAV_CMD":
            continue
        for entry in enum.findall("entry"):
            out += [f"#### {entry.get('name')} ({entry.get('value')})", "", _text(entry.find("description")), "",
                    "| param | label | unit | description |", "| --- | --- | --- | --- |"]
            for p in entry.findall("param"):
                out.append(f"| {p.get('index')} | {p.get('label') or '-'} | {p.get('units') or '-'} "
                           f"| {_cell(_text(p))} |")
            out.append("")
    out += ["### Enums", ""]
    for enum in root.iter("enum"):
        if enum.get("name") == "MAV_CMD":
            continue
        bitmask = " (bitmask)" if enum.get("bitmask") == "true" else ""
        out += [f"#### {enum.get('name')}{bitmask}", "", _text(enum.find("description")), "",
                "| value | name | description |", "| --- | --- | --- |"]
        for entry in enum.findall("entry"):
            out.append(f"| {entry.get('value')} | `{entry.get('name')}` | {_cell(_text(entry.find('description')))} |")
        out.append("")
    return "\n".join(out).rstrip() + "\n"


# --- the hardware rig's effects: every key whose value differs between the two plants --------------

def hardware_effects_page() -> str:
    from rig_emulator.config.loader import load_config
    from rig_emulator.config.schema import SCHEMA

    hw = load_config(airframe="hilms")
    ideal = load_config(airframe="hilms-ideal")
    rows = []
    for key, spec in SCHEMA.items():
        if key in ("airframe.name",) or _value(hw[key]) == _value(ideal[key]):
            continue
        rows.append(f"| `{key}` | {_cell(spec.unit) or '-'} | `{_value(ideal[key])}` | `{_value(hw[key])}` "
                    f"| {_cell(spec.doc)} |")
    return "\n".join([
        "Generated from the presets: every parameter whose value on the hardware rig `hilms` "
        "(`rig_emulator/presets/hardware/hilms.toml` over `rig_emulator/presets/rig.toml`) differs from "
        "the ideal plant `hilms-ideal`, with the schema's description.",
        "",
        "| key | unit | `hilms-ideal` | `hilms` | what it is |",
        "| --- | --- | --- | --- | --- |",
        *rows,
    ]) + "\n"


# --- Table 6 on both plants (a few seconds once the step loop is compiled) -----------------------

TABLE6_COMMAND = "rig-emulator simulate --scenario helix --strategy STRATEGY --seed 0 [--airframe hilms-ideal]"


def table6_page() -> str:
    from protocol.mean_error import PAPER_TABLE_6 as TABLE6
    from rig_emulator.api import simulate

    cols = ("phi_deg", "theta_deg", "psi_deg", "x_m", "y_m", "z_m")
    out = ["Generated by `bash scripts/docs.sh` (CI checks it): the mean errors of Eq. 45 on the helix of Eq. 46, "
           f"seed 0, as `{TABLE6_COMMAND}` prints them, next to the paper's Table 6. Angles in degrees, "
           "positions in metres.", "",
           "| controller | plant | ME phi | ME theta | ME psi | ME X | ME Y | ME Z |",
           "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for strategy in ("smc-flc", "flc"):
        paper = TABLE6[strategy]
        out.append(f"| {strategy} | paper | " + " | ".join(f"{paper[c]:.4f}" for c in cols) + " |")
        for airframe in ("hilms", "hilms-ideal"):
            me = simulate("helix", strategy=strategy, seed=0, airframe=airframe).mean_errors()
            out.append(f"| {strategy} | {airframe} | " + " | ".join(f"{me[c]:.3f}" for c in cols) + " |")
    return "\n".join(out) + "\n"


def hover_thrust_page() -> str:
    """What ``rig-emulator hover-thrust`` measures (seed 0, both plants), as tables."""
    from rig_emulator.headless.hover_thrust import measure_hover_fraction

    ms = [measure_hover_fraction(airframe) for airframe in ("hilms", "hilms-ideal")]
    m0 = ms[0]
    out = [f"Generated by `bash scripts/docs.sh` (CI checks it): the figures `rig-emulator hover-thrust` prints, "
           f"seed 0, a {m0.settle_s:g} s position hold at 2 m, then {m0.window_s:g} s of level attitude set-points "
           "at each thrust (a fraction of full thrust, SET_ATTITUDE_TARGET.thrust).", "",
           "| plant | hovers at (measured) | MPC_THR_HOVER after the hold | thrust chain, steady | m g / u1_max |",
           "| --- | --- | --- | --- | --- |"]
    out += [f"| {m.airframe} | {m.measured:.4f} | {m.served:.4f} | {m.steady:.4f} | {m.nominal:.4f} |" for m in ms]
    out += ["", f"The trials the measurement flew (the climb of the onboard position over {m0.window_s:g} s; a trial "
                "that sinks to 0.3 m ends there):", "",
            "| plant | thrust | vertical acceleration | climb, onboard | climb, SIM_STATE | flown |",
            "| --- | --- | --- | --- | --- | --- |"]
    for m in ms:
        out += [f"| {m.airframe} | {t.fraction:.4f} | {t.accel_m_s2:+.4f} m/s^2 | {t.climb_m:+.3f} m | "
                f"{t.climb_sim_state_m:+.3f} m | {t.duration_s:.2f} s |" for t in m.trials]
    return "\n".join(out) + "\n"


# --- benchmark results (expensive: written from a results file of `python -m benchmarks`) -----------

def benchmarks_page(results_path: Path, command: str) -> str:
    import json

    sys.path.insert(0, str(ROOT))
    from benchmarks.harness import format_value

    doc = json.loads(Path(results_path).read_text())
    meta, settings = doc["meta"], doc["settings"]
    out = [f"Written by `python scripts/docs_gen.py --benchmarks FILE.json --benchmarks-command '{command}'` "
           f"from the results of `{command}`: {settings['repeat']} fresh-process repetitions per probe, medians "
           f"and min..max over them. Machine: {meta.get('cpu')} x{meta.get('cpu_count')}, Python "
           f"{meta.get('python')}, load average {meta.get('loadavg_start')} at the start and "
           f"{meta.get('loadavg_end')} at the end (other work shares the cores: a ratio against a "
           "reference measured in the same repetition is the figure to read).", "",
           "| benchmark | metric | median | min..max | unit | reference | target |",
           "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, entry in doc["benchmarks"].items():
        if entry["status"] != "ok":
            out.append(f"| {name} | failed: {_cell(entry.get('error', ''))} | | | | | |")
            continue
        for m in entry["metrics"]:
            spread = "" if m["low"] is None or m["high"] is None else \
                f"{format_value(m['low'])}..{format_value(m['high'])}"
            targets = "; ".join(
                f"{t['op']} {format_value(t['value'])}: "
                f"{'met' if (m['value'] >= t['value'] if t['op'] == '>=' else m['value'] <= t['value']) else 'NOT met'}"
                for t in m["targets"] if m["value"] is not None)
            out.append(f"| {name} | {_cell(m['name'])} | {format_value(m['value'])} | {spread} | {_cell(m['unit'])} "
                       f"| {_cell(m['reference'] or '')} | {_cell(targets)} |")
    return "\n".join(out) + "\n"


# --- the reproduction's summary (expensive: written from a `rig-gcs reproduce` output) --------------

MACHINE_NOTE = ""


def reproduce_page(out_dir: Path, command: str, timing: Path | None) -> str:
    import json

    report = (Path(out_dir) / "report.md").read_text()
    head = "## The paper, the hardware rig and the ideal plant side by side"
    if head not in report:
        raise SystemExit(f"docs_gen: {out_dir}/report.md has no section {head!r} (run reproduce on both plants)")
    body = report.split(head, 1)[1].split("\n## ", 1)[0].strip()
    lines = body.splitlines()
    body = "\n".join(ln for ln in lines if not ln.startswith("The verdicts and sections below are"))
    when = ""
    if timing is not None:
        t = json.loads(Path(timing).read_text())
        runs = t.get("headless_runs", t.get("runs"))
        parts = [f"{runs} headless runs" if runs is not None else "",
                 f"{t['wall_s']:.1f} s wall" if "wall_s" in t else "",
                 f"{t['cpu_s']:.1f} s CPU" if "cpu_s" in t else ""]
        machine = MACHINE_NOTE
        when = (" It took " + ", ".join(p for p in parts if p) + (f" on {machine}" if machine else "") + ".")
    return (f"Written by `python scripts/docs_gen.py --reproduce DIR` from the report of `{command}`"
            f" (`DIR/report.md`, its first table).{when}\n\n{body}\n")


# --- your controllers next to the paper's (expensive: written from a `rig-gcs reproduce --controller` output) --

def _section(report: str, title: str, path: Path) -> str:
    for part in report.split("\n## ")[1:]:
        if part.startswith(title):
            return part.split("\n", 1)[1].strip()
    raise SystemExit(f"docs_gen: {path} has no section {title!r} (run reproduce with --controller)")


def _when(timing: Path | None, machine: str) -> str:
    if timing is None:
        return ""
    t = json.loads(Path(timing).read_text())
    parts = [f"{t['headless_runs']} headless runs" if "headless_runs" in t else "",
             f"{t['simulated_s']:.0f} simulated s" if "simulated_s" in t else "",
             f"{t['wall_s']:.0f} s wall" if "wall_s" in t else ""]
    return " It took " + ", ".join(p for p in parts if p) + (f" on {machine}" if machine else "") + "."


def compare_pages(out_dir: Path, command: str, timing: Path | None, machine: str) -> dict[str, str]:
    """docs/generated/compare-verdicts.md (what the command prints and every plug-in's verdicts) and
    compare-helix.md (the line-then-helix table) from ``DIR/report.md`` and the summary in ``DIR/results.json``."""
    path = Path(out_dir) / "report.md"
    report = path.read_text()
    verdicts = _section(report, "Verdicts", path)
    results = Path(out_dir) / "results.json"
    summary = json.loads(results.read_text()).get("comparison", {}).get("summary")
    if not summary:
        raise SystemExit(f"docs_gen: no comparison summary in {results} (run reproduce with --controller)")
    intro = (f"Written by `python scripts/docs_gen.py --compare DIR` from the report of `{command}` (`DIR/report.md`)."
             + _when(timing, machine))
    helix = _section(report, "5. Line-then-helix", path)
    table = "\n".join(ln if ln.startswith("|") else "\n" + ln + "\n" for ln in helix.splitlines()
                      if ln.startswith(("|", "`"))).strip()
    return {
        "compare-verdicts.md": (f"{intro} It prints\n\n```text\n" + "\n".join(summary) + "\n```\n\n"
                                "and writes every plug-in's verdicts to `DIR/report.md`:\n\n"
                                "??? note \"Every plug-in's verdicts against each of the paper's controllers\"\n\n"
                                + textwrap.indent(verdicts, "    ") + "\n"),
        "compare-helix.md": (f"From the report of `{command}`, section \"Line-then-helix\" (mean over the "
                             "seeds, the smallest and largest seed in brackets):\n\n" + table + "\n"),
    }


# --- the paper fit's held-out tables (expensive: written from `rig-gcs identify --paper --held-out` files) --

def held_out_page(path: Path, wall_s: float | None, machine: str) -> str:
    """docs/generated/held-out-NAME.md from the ``-o FILE.json`` of ``rig-gcs identify --paper --held-out``."""
    from gcs_tools.identify.held_out import markdown

    doc = json.loads(Path(path).read_text())
    took = "" if wall_s is None else f" It took {wall_s:.0f} s wall" + (f" on {machine}" if machine else "") + "."
    return (f"Written by `python scripts/docs_gen.py --held-out FILE.json` from the `-o` file of the command below "
            f"({doc['evaluated_points']} evaluated points).{took}\n\n" + markdown(doc, doc.get("command")) + "\n")


# --- the paper fit's refit with the priors (expensive: written from `rig-gcs identify --paper --json` files) --

def refit_page(path: Path, machine: str) -> str:
    """docs/generated/paper-refit.md from the ``--json FILE`` of a ``rig-gcs identify --paper`` fit: each
    fitted key's start (the shipped value the fit starts from) and its fitted value with the fit's sigma."""
    from rig_emulator.config.schema import SCHEMA

    doc = json.loads(Path(path).read_text())

    def unit_of(key: str) -> str:
        spec = SCHEMA.get(re.sub(r"\[.*\]$", "", key))
        return spec.unit if spec is not None else ""

    def fmt(v, unit: str, sigma=None) -> str:
        scale, unit = (1e3, "ms") if unit == "s" else (1.0, unit)
        text = f"{v * scale:.3g}" + ("" if sigma is None else f" +- {sigma * scale:.2g}")
        return text + (f" {unit}" if unit else "")

    rows = ["| key | shipped (the fit's start) | refit | prior |", "|---|---|---|---|"]
    for p in doc["params"]:
        u = unit_of(p["key"])
        prior = "-" if not p.get("prior") else fmt(p["prior"][0], u, p["prior"][1])
        bound = " (at a bound)" if p.get("at_bound") else ""
        rows.append(f"| `{p['key']}` | {fmt(p['start'], u)} | {fmt(p['value'], u, p.get('sigma'))}{bound} | {prior} |")
    took = (f"{doc['evaluations']} points, {doc['runs']} headless runs, {doc['wall_s']:.0f} s wall"
            + (f" on {machine}" if machine else ""))
    return (f"Written by `python scripts/docs_gen.py --refit FILE.json` from the `--json` file of `{doc['command']}` "
            f"({took}; fit status: {doc['status']}). Sigma is the fit's one-sigma uncertainty from its Jacobian.\n\n"
            + "\n".join(rows) + "\n")


# --- the stability analysis (cheap, but its solver's last digits vary by machine: written, not checked) --

def stability_page() -> str:
    from gcs_tools.stability import analyse, load_settings
    from rig_emulator.config.loader import load_config

    md = analyse(load_config(airframe="hilms"), load_settings({})).to_markdown().strip()
    lines = md.splitlines()
    if lines and lines[0].startswith("## "):
        lines = lines[1:]
    return ("Written by `python scripts/docs_gen.py --stability`: the output of `rig-gcs stability` (the default "
            "airframe, `hilms`; the FLC gains are the same on both plants).\n" + "\n".join(lines) + "\n")


# --- all -----------------------------------------------------------------------------------------

def pages() -> dict[str, str]:
    with redirect_stdout(io.StringIO()):  # importing the link layer may print nothing, but keep stdout ours
        result = {**cli_pages(), "parameters.md": parameters_page(), "mavlink-streams.md": streams_page(),
                  "dialect.md": dialect_page(), "hardware-effects.md": hardware_effects_page(),
                  "table6.md": table6_page(), "hover-thrust.md": hover_thrust_page()}
    return result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true",
                    help="compare with the committed files instead of writing them; exit 1 on a difference")
    ap.add_argument("--benchmarks", metavar="FILE.json",
                    help="also write docs/generated/benchmarks.md from this `python -m benchmarks` results file")
    ap.add_argument("--benchmarks-command", default="python -m benchmarks",
                    help="the command that made --benchmarks' file, quoted on the page")
    ap.add_argument("--reproduce", metavar="DIR", help="also write docs/generated/reproduce-summary.md from the "
                                                      "output directory of a full `rig-gcs reproduce -o DIR`")
    ap.add_argument("--reproduce-command", default="rig-gcs reproduce -o DIR",
                    help="the command that made --reproduce's directory, quoted on the page")
    ap.add_argument("--reproduce-timing", metavar="FILE.json", help="its --timing file (time and runs on the page)")
    ap.add_argument("--machine", default="", help="the machine the expensive run was made on, in words, for the page")
    ap.add_argument("--identify-study", metavar="FILE.json",
                    help="also write docs/generated/identify-calibration.md from the --json file of "
                         "`rig-gcs identify --calibration-study N`")
    ap.add_argument("--identify-study-command", default="rig-gcs identify --calibration-study 20 --study-seed 1",
                    help="the command that made --identify-study's file, quoted on the page")
    ap.add_argument("--compare", metavar="DIR",
                    help="also write docs/generated/compare-verdicts.md and compare-helix.md from the output "
                         "directory of `rig-gcs reproduce --controller ...`")
    ap.add_argument("--compare-command", default="rig-gcs reproduce -o DIR --controller ...",
                    help="the command that made --compare's directory, quoted on the page")
    ap.add_argument("--compare-timing", metavar="FILE.json", help="its --timing file (runs and time on the page)")
    ap.add_argument("--held-out", metavar="FILE.json", help="also write docs/generated/held-out-NAME.md from the "
                                                             "-o file of `rig-gcs identify --paper --held-out ...`")
    ap.add_argument("--held-out-name", default="logo", help="NAME of --held-out's page: %(default)s")
    ap.add_argument("--refit", metavar="FILE.json", help="also write docs/generated/paper-refit.md from the --json "
                                                         "file of a `rig-gcs identify --paper ...` fit")
    ap.add_argument("--held-out-wall", type=float, metavar="S", help="the wall time --held-out's command took (s)")
    ap.add_argument("--stability", action="store_true",
                    help="also write docs/generated/stability.md (rig-gcs stability; needs the analysis extra)")
    args = ap.parse_args(argv)
    if args.stability:
        path = OUT / "stability.md"
        path.write_text(stability_page())
        print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    if args.reproduce:
        global MACHINE_NOTE
        MACHINE_NOTE = args.machine
        path = OUT / "reproduce-summary.md"
        timing = Path(args.reproduce_timing) if args.reproduce_timing else None
        path.write_text(reproduce_page(Path(args.reproduce), args.reproduce_command, timing))
        print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    if args.refit:
        path = OUT / "paper-refit.md"
        path.write_text(refit_page(Path(args.refit), args.machine))
        print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    if args.held_out:
        path = OUT / f"held-out-{args.held_out_name}.md"
        path.write_text(held_out_page(Path(args.held_out), args.held_out_wall, args.machine))
        print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    if args.compare:
        timing = Path(args.compare_timing) if args.compare_timing else None
        for name, text in compare_pages(Path(args.compare), args.compare_command, timing, args.machine).items():
            path = OUT / name
            path.write_text(text)
            print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    if args.identify_study:
        from gcs_tools.identify.study import markdown_page

        path = OUT / "identify-calibration.md"
        study = json.loads(Path(args.identify_study).read_text())
        path.write_text(markdown_page(study, args.identify_study_command, args.machine))
        print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    if args.benchmarks:
        path = OUT / "benchmarks.md"
        path.write_text(benchmarks_page(Path(args.benchmarks), args.benchmarks_command))
        print(f"docs_gen: wrote {path.relative_to(ROOT)}")
        return 0
    stale = []
    for name, text in pages().items():
        path = OUT / name
        if args.check:
            if not path.exists() or path.read_text() != text:
                stale.append(name)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            if not path.exists() or path.read_text() != text:
                path.write_text(text)
                print(f"docs_gen: wrote {path.relative_to(ROOT)}")
    if stale:
        print("docs_gen: out of date (run `bash scripts/docs.sh` and commit): "
              + ", ".join(f"docs/generated/{n}" for n in stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
