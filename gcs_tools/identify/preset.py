"""The fit written as a TOML preset that ``--config`` accepts, with a header saying how it was made.

The body holds the fitted keys only, each as a whole key (a list key with its other elements
as the fit's base configuration has them), so ``rig-emulator simulate --config fit.toml`` (after
the fit's own ``--config`` files, if any) runs the fitted rig. The header (TOML comments)
gives the command, the date, the targets, every fitted value with its uncertainty and every
target's residual.
"""

from __future__ import annotations

import json
import math
from typing import Any

from gcs_tools.identify.params import overrides_for


def _scalar(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return repr(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"{v!r} cannot be written to TOML")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_scalar(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_scalar(x)}" for k, x in v.items()) + " }"
    raise ValueError(f"{v!r} cannot be written to TOML")


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else json.dumps(k)


def _nest(flat: dict) -> dict:
    tree: dict = {}
    for dotted, v in flat.items():
        node = tree
        parts = dotted.split(".")
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        node[parts[-1]] = v
    return tree


def _emit(tree: dict, prefix: str, out: list) -> None:
    plain = {k: v for k, v in tree.items() if not isinstance(v, dict) and not _is_table_list(v)}
    tables = {k: v for k, v in tree.items() if isinstance(v, dict)}
    lists = {k: v for k, v in tree.items() if _is_table_list(v)}
    if plain and prefix:
        out.append(f"[{prefix}]")
    for k, v in plain.items():
        out.append(f"{_key(k)} = {_scalar(v)}")
    if plain:
        out.append("")
    for k, v in tables.items():
        _emit(v, f"{prefix}.{_key(k)}" if prefix else _key(k), out)
    for k, items in lists.items():
        name = f"{prefix}.{_key(k)}" if prefix else _key(k)
        for item in items:
            out.append(f"[[{name}]]")
            for f, x in item.items():
                out.append(f"{_key(f)} = {_scalar(x)}")
            out.append("")


def _is_table_list(v) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def toml_body(flat: dict) -> str:
    out: list = []
    _emit(_nest(flat), "", out)
    return "\n".join(out).rstrip() + "\n"


def fmt_value(v: float, sigma: float | None = None) -> str:
    if sigma is None or not math.isfinite(sigma):
        return f"{v:.6g}" + ("" if sigma is None else " +- inf (not identifiable from these targets)")
    return f"{v:.6g} +- {sigma:.2g}"


def header_lines(result, command: str, date: str, version: str, targets: str, base_text: str) -> list[str]:
    lines = [
        "hilms-sil parameter preset fitted by `rig-gcs identify` (docs/how-to/identify.md); use it with --config.",
        f"command: {command}",
        f"date: {date} (hilms-sil {version})",
        f"fitted on top of: {base_text}",
        f"targets: {targets}",
        f"evaluations: {result.evaluations} parameter points ({result.simulated} simulated in this run, "
        f"{result.runs} headless runs){', record ' + result.record if result.record else ''}; "
        f"wall {result.wall_s:.0f} s; optimiser: {result.status}",
        "",
        "fitted values (1 sigma: Jacobian at the optimum scaled by the residual variance):",
    ]
    for p, v, s, b, st in zip(result.params, result.values, result.sigma, result.at_bound, result.start):
        extra = f"  [bounds {p.lo:g}, {p.hi:g}; start {st:.6g}" + (f"; prior {p.prior[0]:g} +- {p.prior[1]:g}"
                                                                    if p.prior else "") + "]"
        if b:
            extra += f"  AT THE {'LOWER' if b == 'lo' else 'UPPER'} BOUND"
        lines.append(f"  {p.name} = {fmt_value(v, s)}{extra}")
    lines.append("")
    lines += summary_lines(result.summary)
    return lines


def summary_lines(summary: dict) -> list[str]:
    lines = []
    if "targets" in summary:
        lines.append("residuals (paper | fit | ln(fit/paper)):")
        w = max(len(r["metric"]) for r in summary["targets"])
        for r in summary["targets"]:
            fit = r["fit"]
            lines.append(f"  {r['metric']:<{w}}  {r['paper']:.4g} {r['unit']} | "
                         f"{(f'{fit:.4g}' if math.isfinite(fit) else 'n/a')} {r['unit']} | {r['log_residual']:+.3f}")
        lines.append(f"rms log error {summary['rms_log_error']:.3f}; {summary['within_factor_2']}/{summary['n']} "
                     f"within a factor 2; {summary['within_20_pct']}/{summary['n']} within 20 %")
        for c in summary.get("claims", []):
            lines.append(f"  claim {c['claim']}: {'holds' if c['holds'] else 'does not hold'} "
                         f"({c['metric']} = {c['value']:.4g})")
    if "channels" in summary:
        lines.append("residuals (rms of simulated - logged, per log and channel):")
        for r in summary["channels"]:
            lines.append(f"  {r['log']} {r['channel']} ({r['message']}, {r['samples']} samples in {r['intervals']} "
                         f"intervals): "
                         f"{r['rms']:.4g} {r['unit']} rms (scale {r['scale']:g} {r['unit']})"
                         + (f", {r['missing']} not simulated" if r["missing"] else ""))
        lines.append(f"rms of the scaled residuals {summary['rms_scaled']:.4g} over {summary['n']} residuals")
    return lines


def preset_text(result, base_cfg, header: list[str]) -> str:
    """The preset file: ``header`` as comments, then the fitted keys (whole keys, on ``base_cfg``)."""
    flat = overrides_for(result.params, result.values, base_cfg)
    head = "\n".join(("# " + line) if line else "#" for line in header)
    return head + "\n\n" + toml_body(flat)
