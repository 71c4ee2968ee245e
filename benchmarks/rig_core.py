"""rig-core: one rig, 1 kHz physics, full controller, against RotorPy in the same run.

Each scenario is measured twice: the **core** (``sensors.simulate = false``: physics,
guidance and controllers on the true state, the core's own figure) and the **full-fidelity
rig** (the default: five IMU modules with magnetometers, four load cells, calibration,
ensemble, complementary filter, load-cell filter, onboard Eq. 1, the figure users
see). Their ratio is the sensing chain's cost (target: within 2x).

The probe calls ``rig_emulator.api.simulate(scenario, strategy, duration, seed)`` in a
fresh process:

1. the first call pays numba's compilation (repetition 1, whose cache directory is
   empty) or its cache load (later repetitions); its wall time around the call is
   reported as the warm-up figure;
2. ``inner`` further identical calls measure the steady state. Their real-time
   factor is ``SimResult.sim_time_s / SimResult.wall_time_s``, i.e. simulated time
   over the time spent in the compiled loop (the API excludes compilation). The
   end-to-end factor, timed around the whole call, is reported as well.

Targets: >= 200x real time for the core, >= 300x real time and >= 400x
RotorPy's bare 1 kHz loop with its IMU (``rotorpy-1khz-imu``).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable

from .harness import (
    BenchmarkUnavailable,
    Metric,
    ProbeStats,
    REGISTRY,
    Target,
    benchmark,
    median,
    paired_ratio_metric,
)
from .rotorpy_reference import ROTORPY_BARE

SCENARIOS = ("hover", "helix")
STRATEGY = "smc-flc"
DURATION_S = 30.0
QUICK_DURATION_S = 5.0

RTF_TARGETS = (Target(">=", 200.0, "sweeps of many rigs"), Target(">=", 300.0, "full fidelity"))
VS_ROTORPY_TARGETS = (Target(">=", 400.0, "against RotorPy, the same run"),)


def _import_simulate() -> Callable:
    try:
        from rig_emulator.api import simulate
    except ImportError as exc:
        raise BenchmarkUnavailable(
            "rig-core needs rig_emulator.api.simulate(scenario, strategy='smc-flc', duration=10.0, "
            f"seed=0, **overrides) -> SimResult, and importing it failed: {type(exc).__name__}: {exc}"
        ) from None
    return simulate


def _source_label() -> str:
    """Which rig sources were measured: the digest naming the numba cache, when available."""
    try:
        from rig_emulator import _jit
    except ImportError:
        return "unknown"
    return os.path.basename(getattr(_jit, "CACHE_DIR", "")) or "unknown"


def _check(result, duration: float) -> None:
    for attr in ("sim_time_s", "wall_time_s", "steps", "mean_errors"):
        if not hasattr(result, attr):
            raise TypeError(f"SimResult lacks {attr!r} (got {type(result).__name__})")
    if not result.wall_time_s > 0:
        raise ValueError(f"SimResult.wall_time_s must be > 0, got {result.wall_time_s!r}")
    if not math.isclose(result.sim_time_s, duration, rel_tol=0.01, abs_tol=0.002):
        raise ValueError(f"simulated {result.sim_time_s} s where {duration} s were requested")
    if result.steps < 1:
        raise ValueError(f"SimResult.steps must be >= 1, got {result.steps!r}")


def rig_simulate_probe(scenario: str, strategy: str, duration: float, seed: int, inner: int,
                       sensors: bool = True, _simulate: Callable | None = None, airframe: str | None = None) -> dict:
    """Warm-up and steady-state speed of ``rig_emulator.api.simulate``.

    ``SimResult.mean_errors`` may be a mapping or a method returning one.

    ``_simulate`` replaces the API (tests only; the harness never passes it).
    """
    if inner < 1:
        raise ValueError(f"inner must be >= 1, got {inner}")
    t0 = time.perf_counter()
    simulate = _simulate if _simulate is not None else _import_simulate()
    import_s = time.perf_counter() - t0
    source = _source_label() if _simulate is None else "stand-in"

    kwargs = {} if sensors else {"overrides": {"sensors.simulate": False}}
    if airframe is not None:  # None: the API's default plant (the hardware rig)
        kwargs["airframe"] = airframe
    t1 = time.perf_counter()
    first = simulate(scenario, strategy=strategy, duration=duration, seed=seed, **kwargs)
    first_call_s = time.perf_counter() - t1
    _check(first, duration)

    rtfs, e2e, walls, last = [], [], [], first
    for _ in range(inner):
        t2 = time.perf_counter()
        last = simulate(scenario, strategy=strategy, duration=duration, seed=seed, **kwargs)
        outer = time.perf_counter() - t2
        _check(last, duration)
        rtfs.append(last.sim_time_s / last.wall_time_s)
        e2e.append(last.sim_time_s / outer)
        walls.append(last.wall_time_s)

    figs = {
        "source": source,
        "rtf": median(rtfs),
        "rtf_end_to_end": median(e2e),
        "wall_time_s": median(walls),
        "us_per_step": median(walls) / last.steps * 1e6,
        "sim_time_s": float(last.sim_time_s),
        "steps": int(last.steps),
        "physics_hz": last.steps / last.sim_time_s,
        "import_s": import_s,
        "first_call_s": first_call_s,
        "first_call_loop_s": float(first.wall_time_s),
        "warmup_overhead_s": first_call_s - float(first.wall_time_s),
    }
    errors = last.mean_errors() if callable(last.mean_errors) else last.mean_errors
    for k, v in dict(errors).items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            figs[f"mean_error.{k}"] = float(v)
    return figs


VARIANTS = {"core": False, "full": True, "ideal": True}  # name -> sensors simulated
#: name -> airframe: the default plant (the hardware rig ``hilms``) or the ideal plant
VARIANT_AIRFRAME = {"core": None, "full": None, "ideal": "hilms-ideal"}
CORE_TARGETS = (Target(">=", 200.0, "sweeps of many rigs"),)
FULL_TARGETS = (Target(">=", 300.0, "full fidelity"), Target(">=", 500.0, "quiet machine"))
COST_TARGETS = (Target("<=", 2.0, "the sensor models at most halve the speed"),)


def _probe_name(scenario: str, variant: str = "full") -> str:
    return f"rig-{scenario}-{STRATEGY}-{variant}"


for _sc in SCENARIOS:
    for _variant, _sensors in VARIANTS.items():
        REGISTRY.add_probe(
            _probe_name(_sc, _variant), rig_simulate_probe,
            params={"scenario": _sc, "strategy": STRATEGY, "duration": DURATION_S, "seed": 0, "inner": 3,
                    "sensors": _sensors, "airframe": VARIANT_AIRFRAME[_variant]},
            quick={"duration": QUICK_DURATION_S, "inner": 1},
            description=f"rig_emulator.api.simulate({_sc!r}, {STRATEGY!r}), 1 kHz physics, "
                        + ("full sensing chain" if _sensors else "no sensor models (core)")
                        + (", the ideal plant (hilms-ideal)" if _variant == "ideal" else ", the hardware rig"),
        )


@benchmark("rig-core",
           probes=(ROTORPY_BARE,) + tuple(_probe_name(s, v) for s in SCENARIOS for v in VARIANTS),
           description="one rig, 1 kHz physics, smc-flc, hover and helix, core and full fidelity; "
                       "vs RotorPy in the same run")
def rig_core(stats: dict[str, ProbeStats]) -> list[Metric]:
    ref = stats[ROTORPY_BARE]
    out = [ref.metric("rtf", "RotorPy bare loop (reference)", "x real time")]
    for sc in SCENARIOS:
        core = stats[_probe_name(sc, "core")]
        out.append(core.metric("rtf", f"{sc}: core real-time factor (no sensor models)", "x real time",
                               targets=CORE_TARGETS, note="true-state feedback: the physics and the control laws alone"))
        out.append(paired_ratio_metric(core, "rtf", ref, "rtf", f"{sc}: core speed vs RotorPy"))
        s = stats[_probe_name(sc, "full")]
        out.append(s.metric("rtf", f"{sc}: full-fidelity real-time factor", "x real time", targets=FULL_TARGETS,
                            note="5 IMU modules + magnetometers, 4 load cells, estimators; steady state"))
        out.append(paired_ratio_metric(s, "rtf", ref, "rtf", f"{sc}: full-fidelity speed vs RotorPy",
                                       targets=VS_ROTORPY_TARGETS))
        out.append(paired_ratio_metric(core, "rtf", s, "rtf", f"{sc}: sensing cost (core / full)",
                                       targets=COST_TARGETS))
        ideal = stats[_probe_name(sc, "ideal")]
        out.append(ideal.metric("rtf", f"{sc}: ideal plant (hilms-ideal) full-fidelity real-time factor",
                                "x real time", note="the same rig without the hardware effects"))
        out.append(paired_ratio_metric(s, "rtf", ideal, "rtf", f"{sc}: hardware rig speed vs the ideal plant",
                                       note="the hardware effects' cost"))
        out.append(s.metric("rtf_end_to_end", f"{sc}: real-time factor end to end", "x real time",
                            note="timed around the whole simulate() call (setup and result "
                                 "building included)"))
        out.append(s.metric("us_per_step", f"{sc}: time per physics step", "us"))
        hz = s.median("physics_hz")
        out.append(Metric(f"{sc}: physics steps per simulated second", hz, "Hz",
                          note="" if abs(hz - 1000.0) <= 10.0 else "NOT the 1 kHz this benchmark is defined at"))
        out.append(Metric(f"{sc}: first call, cold numba cache", s.first("first_call_s"), "s",
                          note="repetition 1 starts with an empty numba cache: compile + one run"))
        if len(s.runs) > 1:
            out.append(s.metric("first_call_s", f"{sc}: first call, warm numba cache", "s", skip_first=True))
        errs = sorted(k for k in s.runs[-1] if k.startswith("mean_error."))
        for k in errs:
            out.append(s.metric(k, f"{sc}: {k} (sanity)", "as reported"))
    return out
