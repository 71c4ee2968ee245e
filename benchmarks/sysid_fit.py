"""sysid-fit: the regression identification of one identification flight (``rig-gcs identify --tlog``,
method regression) on the default ``hilms`` rig.

The probe flies the scenario ``sysid`` (120 s, FLC) once, writes its .tlog (neither is timed), then times
the whole fit of that log: reading the .tlog, the motor chain, the torque balance, the random torque and
the model checks (:func:`gcs_tools.identify.regression.identify_log`), ``inner`` times. Figures: the fit's
wall time (median) and its CPU time; target: the whole fit under 60 s of wall time on 2 cores.
"""

from __future__ import annotations

import os
import tempfile
import time
from statistics import median

from .harness import Metric, ProbeStats, Target, benchmark, probe

NAME = "sysid-fit-hilms"


@probe(NAME, params={"seed": 1, "inner": 2}, quick={"inner": 1},
       description="rig-gcs identify --tlog on a 120 s sysid flight of hilms (regression), wall and CPU time")
def sysid_fit_probe(seed: int, inner: int) -> dict:
    from gcs_tools.identify.regression import identify_log
    from rig_emulator.config.loader import load_config
    from rig_emulator.link.telemetry.tlog_export import export_tlog
    from rig_emulator.simulation.run import Simulation

    cfg = load_config(airframe="hilms", scenario="sysid", overrides={"control.strategy": "flc", "sim.seed": seed})
    base = load_config(airframe="hilms", scenario="sysid")
    walls, cpus = [], []
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "sysid.tlog")
        export_tlog(Simulation(cfg).run(), path)
        for _ in range(inner):
            w0, c0 = time.perf_counter(), time.process_time()
            result = identify_log(path, base)
            walls.append(time.perf_counter() - w0)
            cpus.append(time.process_time() - c0)
    return {"fit_wall_s": median(walls), "fit_cpu_s": median(cpus), "explained": float(result.explained)}


@benchmark("sysid-fit", probes=(NAME,), description="regression identification of a sysid log, hilms")
def sysid_fit(stats: dict[str, ProbeStats]) -> list[Metric]:
    s = stats[NAME]
    return [
        s.metric("fit_wall_s", "whole fit of a 120 s sysid log: wall time", "s",
                 targets=(Target("<=", 60.0, "identification on 2 cores"),)),
        s.metric("fit_cpu_s", "whole fit: CPU time of the process", "s"),
    ]
