"""hardware-rig: the hardware-faithful rig ``hilms`` against the ideal plant ``hilms-ideal``.

Both fly the helix with the built-in ``smc-flc`` strategy, the full sensing chain and 1 kHz
physics, in fresh processes with a warm numba cache for the steady state (the probes
``rig-helix-smc-flc-full`` and ``rig-helix-smc-flc-ideal`` of :mod:`benchmarks.rig_core`, shared:
``python -m benchmarks --only rig-core,hardware-rig`` runs them once). Figures:

* each plant's real-time factor (``SimResult.sim_time_s / wall_time_s``, median of the in-process
  calls after the first, then over repetitions); the target: the full-fidelity ``hilms``
  rig at least 500x real time on a quiet 2-core machine;
* **speed of hilms / speed of hilms-ideal**, paired by repetition (the two probes run back to
  back): the hardware effects' cost, the figure that carries over from a busy machine (the
  ideal plant did 650-700x on a quiet one, so 500x needs this ratio at about 0.75 or above);
* the first call of repetition 1 (empty numba cache: compile + one run) and of the later ones
  (cache load), for both: the effects must not slow the cold compile.

Absolute figures on a shared machine are noisy; quote them with the load (``loadavg`` in the
JSON). The ratio alone cannot judge a change of the step loop (a change that slows the ideal
plant improves it): ``python -m benchmarks.plugin_overhead --base COMMIT --airframe hilms
--airframe ideal`` compares both plants with an earlier commit (both trees, same run).
"""

from __future__ import annotations

from .harness import Metric, ProbeStats, Target, benchmark, paired_ratio_metric
from .rig_core import _probe_name

HILMS = _probe_name("helix", "full")
IDEAL = _probe_name("helix", "ideal")
HILMS_TARGETS = (Target(">=", 500.0, "quiet machine"),)


@benchmark("hardware-rig", probes=(HILMS, IDEAL),
           description="hilms (hardware effects) vs hilms-ideal, helix, smc-flc, 1 kHz, same run")
def hardware_rig(stats: dict[str, ProbeStats]) -> list[Metric]:
    hw, ideal = stats[HILMS], stats[IDEAL]
    out = [
        hw.metric("rtf", "hilms: real-time factor", "x real time", targets=HILMS_TARGETS,
                  note="the default airframe: every hardware effect on; quiet-machine target"),
        ideal.metric("rtf", "hilms-ideal: real-time factor", "x real time", note="the ideal plant, same run"),
        paired_ratio_metric(hw, "rtf", ideal, "rtf", "hilms speed / hilms-ideal speed",
                            note="paired by repetition; the hardware effects' cost"),
        hw.metric("us_per_step", "hilms: time per physics step", "us"),
        ideal.metric("us_per_step", "hilms-ideal: time per physics step", "us"),
        Metric("hilms: first call, cold numba cache", hw.first("first_call_s"), "s",
               note="repetition 1: compile + one run"),
        Metric("hilms-ideal: first call, cold numba cache", ideal.first("first_call_s"), "s",
               note="repetition 1: compile + one run (the same compiled code)"),
    ]
    if len(hw.runs) > 1:
        out.append(hw.metric("first_call_s", "hilms: first call, warm numba cache", "s", skip_first=True))
    return out
