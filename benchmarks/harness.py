"""Machinery of the benchmark suite: registry, subprocess runner, statistics, table, JSON.

Vocabulary
----------
*probe*
    A module-level function that measures something and returns a flat mapping of
    raw figures (``{"rtf": 0.41, "wall_time_s": 7.3, ...}``). The harness runs each
    probe once per repetition in a **fresh Python subprocess**, so import time,
    numba compilation and numba's on-disk cache behave exactly as for a user
    starting a new process. A probe is registered with parameters for the full run
    and for ``--quick``.
*benchmark*
    A function that turns the collected runs of the probes it needs into
    :class:`Metric` objects (value, unit, and for a ratio the name of the reference
    probe it was divided by). One benchmark may reuse another's probes: a shared
    reference (e.g. RotorPy) is measured once per repetition and used by all.

Repetitions are interleaved (rep 1 of every probe, then rep 2 of every probe, ...)
so that a slow drift of the machine's load affects the subject and its reference
alike. Each probe gets its own numba cache directory, created empty for the suite
run and shared by that probe's repetitions: repetition 1 pays the cold compile,
later repetitions load the cache, and the two are reported separately.

Nothing here asserts on timings; targets are printed as met / not met.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

REPO_ROOT = Path(__file__).resolve().parent.parent
SCHEMA = "hilms-sil-bench/1"

Scalar = float | int | str | bool | None


class BenchmarkError(RuntimeError):
    """A benchmark or probe could not be run or produced unusable figures."""


class BenchmarkUnavailable(BenchmarkError):
    """A probe's prerequisite (a package, an API) is missing; the message says what to do."""


class ProbeFailed(BenchmarkError):
    """A probe's subprocess failed; carries the probe name and the child's error text."""

    def __init__(self, probe: str, message: str):
        super().__init__(f"probe {probe!r} failed: {message}")
        self.probe = probe
        self.detail = message


# --------------------------------------------------------------------------------------
# Pure helpers
# --------------------------------------------------------------------------------------


def median(values: Iterable[float]) -> float:
    """Median of finite numbers; raises :class:`BenchmarkError` on an empty or non-finite input."""
    xs = [float(v) for v in values]
    if not xs:
        raise BenchmarkError("median of no values")
    bad = [v for v in xs if not math.isfinite(v)]
    if bad:
        raise BenchmarkError(f"median of non-finite values: {bad}")
    xs.sort()
    n = len(xs)
    mid = n // 2
    return xs[mid] if n % 2 else 0.5 * (xs[mid - 1] + xs[mid])


def ratio(subject: float, reference: float) -> float:
    """``subject / reference`` with a clear error when the reference is not a positive number."""
    subject = float(subject)
    reference = float(reference)
    if not math.isfinite(subject) or not math.isfinite(reference):
        raise BenchmarkError(f"ratio of non-finite figures: {subject} / {reference}")
    if reference <= 0.0:
        raise BenchmarkError(f"ratio against a non-positive reference: {subject} / {reference}")
    return subject / reference


@dataclasses.dataclass(frozen=True)
class Target:
    """A goal for a metric, e.g. ``Target(">=", 200, "sweeps of many rigs")``."""

    op: str
    value: float
    label: str

    def __post_init__(self) -> None:
        if self.op not in (">=", "<="):
            raise ValueError(f"Target.op must be '>=' or '<=', got {self.op!r}")

    def met(self, value: float) -> bool:
        return value >= self.value if self.op == ">=" else value <= self.value

    def describe(self) -> str:
        return f"{self.op} {format_value(self.value)} ({self.label})"


@dataclasses.dataclass(frozen=True)
class Metric:
    """One reported figure.

    ``reference`` names the probe the figure was divided by (ratios only);
    ``low``/``high`` give the spread over repetitions when there was one.
    """

    name: str
    value: float
    unit: str
    reference: str | None = None
    targets: tuple[Target, ...] = ()
    low: float | None = None
    high: float | None = None
    note: str = ""

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "value": self.value,
            "unit": self.unit,
            "reference": self.reference,
            "low": self.low,
            "high": self.high,
            "note": self.note,
            "targets": [
                {"op": t.op, "value": t.value, "label": t.label, "met": t.met(self.value)}
                for t in self.targets
            ],
        }


def format_value(v: float | None) -> str:
    """Human formatting: 3 significant figures below 100, integers with separators above."""
    if v is None:
        return "-"
    v = float(v)
    if not math.isfinite(v):
        return str(v)
    a = abs(v)
    if a >= 100:
        return f"{v:,.0f}"
    if a >= 1 or a == 0:
        return f"{v:.3g}" if a < 10 else f"{v:.1f}"
    return f"{v:.3g}"


def format_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Plain-text table with left-aligned columns (pure; used for the console report)."""
    if any(len(r) != len(headers) for r in rows):
        raise ValueError("every row must have as many cells as there are headers")
    widths = [len(h) for h in headers]
    for r in rows:
        for i, cell in enumerate(r):
            widths[i] = max(widths[i], len(cell))
    line = "  ".join("-" * w for w in widths)
    out = ["  ".join(h.ljust(w) for h, w in zip(headers, widths)).rstrip(), line]
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    return "\n".join(out)


def metric_rows(bench_name: str, metrics: Sequence[Metric]) -> list[list[str]]:
    rows = []
    for m in metrics:
        spread = "" if m.low is None or m.high is None else f"{format_value(m.low)}..{format_value(m.high)}"
        targets = "; ".join(
            f"{t.describe()}: {'met' if t.met(m.value) else 'NOT met'}" for t in m.targets
        )
        rows.append([bench_name, m.name, format_value(m.value), spread, m.unit, m.reference or "", targets])
    return rows


TABLE_HEADERS = ("benchmark", "metric", "median", "min..max", "unit", "reference", "target")


# --------------------------------------------------------------------------------------
# Registry
# --------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Probe:
    name: str
    func: Callable[..., Mapping[str, Scalar]]
    params: Mapping[str, Any]
    quick_params: Mapping[str, Any]
    description: str = ""
    cache: str | None = None  # probes naming the same cache group share one numba cache directory

    @property
    def target(self) -> tuple[str, str]:
        """(module, qualified name) by which the worker subprocess imports :attr:`func`."""
        mod = getattr(self.func, "__module__", None)
        qual = getattr(self.func, "__qualname__", "")
        if not mod or "<" in qual or mod == "__main__":
            raise BenchmarkError(
                f"probe {self.name!r}: its function must be defined at module level in an "
                f"importable module (got {mod}.{qual})"
            )
        return mod, qual

    def params_for(self, quick: bool) -> dict[str, Any]:
        return dict(self.quick_params if quick else self.params)


@dataclasses.dataclass(frozen=True)
class Benchmark:
    name: str
    probes: tuple[str, ...]
    summarize: Callable[[Mapping[str, "ProbeStats"]], list[Metric]]
    description: str = ""


class Registry:
    """Named probes and benchmarks. ``REGISTRY`` is the suite's; tests make their own."""

    def __init__(self) -> None:
        self.probes: dict[str, Probe] = {}
        self.benchmarks: dict[str, Benchmark] = {}

    # -- registration ------------------------------------------------------------
    def add_probe(
        self,
        name: str,
        func: Callable[..., Mapping[str, Scalar]],
        params: Mapping[str, Any] | None = None,
        quick: Mapping[str, Any] | None = None,
        description: str = "",
        cache: str | None = None,
    ) -> Probe:
        if name in self.probes:
            raise BenchmarkError(f"probe {name!r} is registered twice")
        params = dict(params or {})
        quick_params = dict(params if quick is None else {**params, **quick})
        for p in (params, quick_params):
            try:
                json.dumps(p)
            except TypeError as exc:
                raise BenchmarkError(f"probe {name!r}: parameters must be JSON-serialisable: {exc}") from None
        probe = Probe(name, func, params, quick_params, description, cache)
        probe.target  # validates importability early
        self.probes[name] = probe
        return probe

    def add_benchmark(
        self,
        name: str,
        probes: Sequence[str],
        summarize: Callable[[Mapping[str, "ProbeStats"]], list[Metric]],
        description: str = "",
    ) -> Benchmark:
        if name in self.benchmarks:
            raise BenchmarkError(f"benchmark {name!r} is registered twice")
        missing = [p for p in probes if p not in self.probes]
        if missing:
            raise BenchmarkError(f"benchmark {name!r} needs unregistered probe(s): {missing}")
        bench = Benchmark(name, tuple(probes), summarize, description)
        self.benchmarks[name] = bench
        return bench

    def probe(self, name: str, params: Mapping[str, Any] | None = None,
              quick: Mapping[str, Any] | None = None, description: str = "", cache: str | None = None):
        """Decorator form of :meth:`add_probe`; returns the function unchanged."""

        def deco(func):
            self.add_probe(name, func, params, quick, description or (func.__doc__ or "").strip().split("\n")[0],
                           cache)
            return func

        return deco

    def benchmark(self, name: str, probes: Sequence[str], description: str = ""):
        """Decorator form of :meth:`add_benchmark`; returns the function unchanged."""

        def deco(func):
            self.add_benchmark(name, probes, func, description or (func.__doc__ or "").strip().split("\n")[0])
            return func

        return deco

    # -- selection ---------------------------------------------------------------
    def select(self, only: Sequence[str] | None) -> list[Benchmark]:
        if not only:
            return list(self.benchmarks.values())
        unknown = [n for n in only if n not in self.benchmarks]
        if unknown:
            raise BenchmarkError(
                f"unknown benchmark(s) {unknown}; available: {sorted(self.benchmarks)}"
            )
        return [self.benchmarks[n] for n in dict.fromkeys(only)]

    def probes_for(self, benches: Sequence[Benchmark]) -> list[Probe]:
        names: dict[str, None] = {}
        for b in benches:
            for p in b.probes:
                names.setdefault(p)
        return [self.probes[n] for n in names]


REGISTRY = Registry()
probe = REGISTRY.probe
benchmark = REGISTRY.benchmark


# --------------------------------------------------------------------------------------
# Statistics over repetitions
# --------------------------------------------------------------------------------------


@dataclasses.dataclass
class ProbeStats:
    """All runs of one probe, in repetition order (run 0 had the cold numba cache)."""

    name: str
    runs: list[dict[str, Scalar]] = dataclasses.field(default_factory=list)

    def values(self, key: str, *, skip_first: bool = False) -> list[float]:
        runs = self.runs[1:] if skip_first else self.runs
        out = []
        for i, r in enumerate(runs):
            if key not in r:
                raise BenchmarkError(f"probe {self.name!r} run {i} did not report {key!r}")
            v = r[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise BenchmarkError(f"probe {self.name!r} reported non-numeric {key!r}={v!r}")
            out.append(float(v))
        return out

    def median(self, key: str, *, skip_first: bool = False) -> float:
        return median(self.values(key, skip_first=skip_first))

    def first(self, key: str) -> float:
        return self.values(key)[0]

    def metric(self, key: str, name: str, unit: str, *, skip_first: bool = False,
               targets: Sequence[Target] = (), note: str = "") -> Metric:
        """Median of ``key`` over the runs, with the min..max spread."""
        vs = self.values(key, skip_first=skip_first)
        if not vs:
            raise BenchmarkError(f"probe {self.name!r}: no runs for {key!r}")
        return Metric(name, median(vs), unit, None, tuple(targets), min(vs), max(vs), note)


def paired_ratio_metric(subject: ProbeStats, key: str, reference: ProbeStats, ref_key: str,
                        name: str, unit: str = "x", targets: Sequence[Target] = (),
                        note: str = "") -> Metric:
    """Ratio of ``subject[key]`` to ``reference[ref_key]``, repetition by repetition.

    Repetition *i* of the subject and of the reference ran back to back, so each
    pair saw the same machine state; the reported value is the median of the
    per-repetition ratios and the spread their min..max.
    """
    a = subject.values(key)
    b = reference.values(ref_key)
    if len(a) != len(b) or not a:
        raise BenchmarkError(
            f"cannot pair {subject.name!r} ({len(a)} runs) with {reference.name!r} ({len(b)} runs)"
        )
    rs = [ratio(x, y) for x, y in zip(a, b)]
    return Metric(name, median(rs), unit, reference.name, tuple(targets), min(rs), max(rs), note)


def paired_difference_metric(subject: ProbeStats, key: str, reference: ProbeStats, ref_key: str,
                             name: str, unit: str, targets: Sequence[Target] = (), note: str = "") -> Metric:
    """``subject[key] - reference[ref_key]`` repetition by repetition (median, min..max).

    For figures where the excess over a floor means more than a ratio (e.g. jitter in ms).
    """
    a = subject.values(key)
    b = reference.values(ref_key)
    if len(a) != len(b) or not a:
        raise BenchmarkError(
            f"cannot pair {subject.name!r} ({len(a)} runs) with {reference.name!r} ({len(b)} runs)"
        )
    ds = [x - y for x, y in zip(a, b)]
    return Metric(name, median(ds), unit, reference.name, tuple(targets), min(ds), max(ds), note)


# --------------------------------------------------------------------------------------
# Running probes in subprocesses
# --------------------------------------------------------------------------------------


def _import_root(module: str) -> Path:
    """Directory to put on ``sys.path`` so that ``module`` imports in a child process."""
    mod = sys.modules.get(module)
    file = getattr(mod, "__file__", None)
    if not file:
        return REPO_ROOT
    path = Path(file).resolve()
    depth = module.count(".") + (1 if path.name == "__init__.py" else 0)
    return path.parents[depth]


def run_probe(probe: Probe, params: Mapping[str, Any], env: Mapping[str, str],
              timeout: float) -> dict[str, Scalar]:
    """Run ``probe`` once in a fresh interpreter; return its figures or raise :class:`ProbeFailed`."""
    module, qualname = probe.target
    roots = [str(_import_root(module)), str(REPO_ROOT)]
    child_env = dict(env)
    child_env["PYTHONPATH"] = os.pathsep.join(
        dict.fromkeys(roots + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    )
    with tempfile.TemporaryDirectory(prefix="hilms-bench-probe-") as tmp:
        result_file = Path(tmp) / "result.json"
        cmd = [
            sys.executable, "-m", "benchmarks._worker",
            "--module", module, "--func", qualname,
            "--params", json.dumps(dict(params)), "--out", str(result_file),
        ]
        try:
            proc = subprocess.run(cmd, cwd=str(REPO_ROOT), env=child_env, capture_output=True,
                                  text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise ProbeFailed(probe.name, f"timed out after {timeout:g} s") from None
        payload = None
        if result_file.exists():
            try:
                payload = json.loads(result_file.read_text())
            except json.JSONDecodeError as exc:
                raise ProbeFailed(probe.name, f"unreadable result file: {exc}") from None
        if payload is None:
            tail = (proc.stderr or proc.stdout or "").strip().splitlines()[-15:]
            raise ProbeFailed(probe.name, f"worker exited with code {proc.returncode} and no result:\n"
                              + "\n".join(tail))
        if "error" in payload:
            raise ProbeFailed(probe.name, payload["error"])
        return payload["figures"]


def varying_labels(runs: Sequence[Mapping[str, Scalar]]) -> dict[str, list[Scalar]]:
    """Text figures (versions, source digests) that differ between repetitions.

    A probe labels what it measured with string figures; if one changes during a
    suite run (e.g. the sources were edited meanwhile), its repetitions did not
    measure the same thing and the report says so.
    """
    out: dict[str, list[Scalar]] = {}
    keys = dict.fromkeys(k for r in runs for k, v in r.items() if isinstance(v, str))
    for k in keys:
        seen = list(dict.fromkeys(r.get(k) for r in runs))
        if len(seen) > 1:
            out[k] = seen
    return out


def machine_info() -> dict[str, Any]:
    from importlib import metadata

    def version(pkg: str) -> str | None:
        try:
            return metadata.version(pkg)
        except metadata.PackageNotFoundError:
            return None

    from gcs_tools.studies.page import cpu_model

    cpu = cpu_model()
    commit = None
    try:
        r = subprocess.run(["git", "rev-parse", "HEAD"], cwd=str(REPO_ROOT), capture_output=True,
                           text=True, timeout=10)
        if r.returncode == 0:
            commit = r.stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        pass
    return {
        "time_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "loadavg_start": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "git_commit": commit,
        "packages": {p: version(p) for p in ("hilms-sil", "numpy", "numba", "scipy", "rotorpy")},
    }


def run_suite(
    registry: Registry,
    *,
    only: Sequence[str] | None = None,
    repeat: int = 5,
    quick: bool = False,
    timeout: float = 900.0,
    log: TextIO | None = None,
) -> dict[str, Any]:
    """Run the selected benchmarks; return the JSON-ready results document."""
    if repeat < 1:
        raise BenchmarkError(f"--repeat must be >= 1, got {repeat}")
    log = log or sys.stderr
    benches = registry.select(only)
    probes = registry.probes_for(benches)
    doc: dict[str, Any] = {
        "schema": SCHEMA,
        "meta": machine_info(),
        "settings": {"repeat": repeat, "quick": quick, "only": list(only or [])},
        "probes": {},
        "benchmarks": {},
    }
    stats = {p.name: ProbeStats(p.name) for p in probes}
    errors: dict[str, str] = {}
    cache_root = tempfile.mkdtemp(prefix="hilms-bench-numba-")
    # One numba cache directory per probe, empty at the start of the suite run: its
    # repetition 1 compiles cold (whatever other probes compiled before), later
    # repetitions load that probe's cache. Probes of one cache group (``cache=``; those
    # that do not measure compilation) share a directory, so only the first compiles.
    envs = {}
    for i, p in enumerate(probes):
        cache = os.path.join(cache_root, f"group-{p.cache}" if p.cache else f"probe-{i}")
        os.makedirs(cache, exist_ok=True)
        envs[p.name] = {**os.environ, "HILMS_NUMBA_CACHE": cache, "NUMBA_CACHE_DIR": cache}
    try:
        for rep in range(repeat):
            for p in probes:
                if p.name in errors:
                    continue
                t0 = time.perf_counter()
                print(f"[rep {rep + 1}/{repeat}] {p.name} ...", end="", file=log, flush=True)
                try:
                    figs = run_probe(p, p.params_for(quick), envs[p.name], timeout)
                except ProbeFailed as exc:
                    errors[p.name] = exc.detail
                    print(f" FAILED ({time.perf_counter() - t0:.1f} s)", file=log, flush=True)
                    continue
                stats[p.name].runs.append(figs)
                print(f" {time.perf_counter() - t0:.1f} s", file=log, flush=True)
    finally:
        shutil.rmtree(cache_root, ignore_errors=True)
    doc["meta"]["loadavg_end"] = list(os.getloadavg()) if hasattr(os, "getloadavg") else None

    for p in probes:
        doc["probes"][p.name] = {
            "description": p.description,
            "function": ".".join(p.target),
            "params": p.params_for(quick),
            "numba_cache": f"shared by group {p.cache!r}" if p.cache else "own",
            "runs": stats[p.name].runs,
            "error": errors.get(p.name),
            "varying_labels": varying_labels(stats[p.name].runs),
        }
    for b in benches:
        failed = [n for n in b.probes if n in errors]
        entry: dict[str, Any] = {"description": b.description, "probes": list(b.probes)}
        if failed:
            entry.update(status="error", metrics=[],
                         error="; ".join(f"{n}: {errors[n]}" for n in failed))
        else:
            try:
                metrics = b.summarize({n: stats[n] for n in b.probes})
                entry.update(status="ok", metrics=[m.to_json() for m in metrics], error=None)
            except BenchmarkError as exc:
                entry.update(status="error", metrics=[], error=str(exc))
            except Exception as exc:  # noqa: BLE001 - a summary's bug must not lose the other benchmarks
                entry.update(status="error", metrics=[], error=f"summary failed: {type(exc).__name__}: {exc}")
        doc["benchmarks"][b.name] = entry
    return doc


def render_report(doc: Mapping[str, Any]) -> str:
    """The console report of a results document: a table, then errors, then context."""
    rows: list[list[str]] = []
    problems: list[str] = []
    for name, entry in doc["benchmarks"].items():
        if entry["status"] != "ok":
            problems.append(f"{name}: {entry['error']}")
            continue
        metrics = [
            Metric(m["name"], m["value"], m["unit"], m["reference"],
                   tuple(Target(t["op"], t["value"], t["label"]) for t in m["targets"]),
                   m["low"], m["high"], m["note"])
            for m in entry["metrics"]
        ]
        rows += metric_rows(name, metrics)
    s = doc["settings"]
    meta = doc["meta"]
    head = (f"hilms-sil benchmarks: {s['repeat']} fresh-process repetition(s) per probe"
            f"{', QUICK smoke run' if s['quick'] else ''}; medians, min..max over repetitions\n"
            f"machine: {meta.get('cpu')} x{meta.get('cpu_count')}, python {meta.get('python')}, "
            f"load {meta.get('loadavg_start')} -> {meta.get('loadavg_end')}")
    parts = [head, ""]
    if rows:
        parts.append(format_table(TABLE_HEADERS, rows))
    grouped: dict[tuple[str, str], list[str]] = {}
    for bn, e in doc["benchmarks"].items():
        for m in e["metrics"]:
            if m["note"]:
                grouped.setdefault((bn, m["note"]), []).append(m["name"])
    if grouped:
        parts += ["", "notes:"] + [f"  {bn} / {', '.join(names)}: {note}"
                                   for (bn, note), names in grouped.items()]
    varying = [f"  {name}: {k} changed between repetitions: {vals}"
               for name, pr in doc["probes"].items() for k, vals in pr.get("varying_labels", {}).items()]
    if varying:
        parts += ["", "WARNING: repetitions did not all measure the same thing:"] + varying
    if problems:
        parts += ["", "ERRORS:"] + [f"  {p}" for p in problems]
    return "\n".join(parts)


def write_json(doc: Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    out = Path(path)
    if out.parent and not out.parent.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=2, sort_keys=False) + "\n")
    return out
