"""The load-cell thrust loop's study (docs/explanation/readings.md, "The load-cell thrust loop"): Fig. 17's
altitude error early vs late per time constant and seed, and what a faulted load cell does to it.

    python -m gcs_tools.studies thrust-loop altitude 0 5 20 60 100 200 500 1000
    python -m gcs_tools.studies thrust-loop faults

The claim verdicts and the Table 4 / Table 6 / Fig. 19 numbers per time constant come from
``rig-gcs reproduce -o DIR --plant hilms --seeds 3 --set motors.thrust_loop_time_constant=T``.
"""

import sys

import numpy as np

from rig_emulator.api import simulate
from rig_emulator.config.loader import load_config
from rig_emulator.control.controller import CS_THRUST_CORR
from rig_emulator.physics.motors import GRAM_FORCE_N
from rig_emulator.simulation import log_layout as L
from rig_emulator.simulation.run import Simulation


def _me(t, z, zd, a, b):
    m = (t >= a) & (t <= b)
    return float(np.mean(np.abs(zd[m] - z[m])))


def altitude(tcs):
    """ME Z of the rig's own altitude over 30-60 s and 200-250 s of the 250 s helix, IIR, seeds 0-2."""
    print("| T (s) | strategy | seed | ME Z 30-60 s (mm) | ME Z 200-250 s (mm) | late - early (mm) |")
    print("|---|---|---|---|---|---|")
    for tc in tcs:
        for s in ("smc-flc", "flc"):
            for seed in (0, 1, 2):
                log = simulate("helix", s, duration=250.0, seed=seed,
                               overrides={"motors.thrust_loop_time_constant": tc,
                                          "estimation.load_cell_filter": "iir"}).log
                t, z, zd = log[:, L.T], log[:, L.POS + 2], log[:, L.POS_DES + 2]
                e, late = _me(t, z, zd, 30.0, 60.0), _me(t, z, zd, 200.0, 250.0)
                print(f"| {tc:g} | {s} | {seed} | {e * 1e3:.1f} | {late * 1e3:.1f} | {(late - e) * 1e3:+.1f} |", flush=True)


def faults():
    """Hover 60 s, smc-flc, seed 0, load cell 2 dead or stuck from 5 s: the corrections and the attitude."""
    print("| fault (t = 5 s, cell 2) | T (s) | corrections at 60 s (gr.F, motors 1-4) | "
          "max abs roll/pitch error 10-60 s (deg) | failsafe |")
    print("|---|---|---|---|---|")
    for mode in ("dead", "stuck"):
        for tc in (0.0, 200.0, 5.0):
            cfg = load_config(airframe="hilms", scenario="hover", overrides={
                "motors.thrust_loop_time_constant": tc, "sim.duration": 60.0, "control.strategy": "smc-flc",
                "faults.events": [{"t": 5.0, "sensor": "load_cell", "index": 2, "mode": mode, "magnitude": 0.0}]})
            sim = Simulation(cfg)
            log = sim.run().log
            m = log[:, L.T] >= 10.0
            err = np.degrees(np.max(np.abs(log[m, L.EULER_DES:L.EULER_DES + 2] - log[m, L.EULER_TRUE:L.EULER_TRUE + 2])))
            c = sim.cstate[CS_THRUST_CORR:CS_THRUST_CORR + 4] / GRAM_FORCE_N
            print(f"| {mode} | {tc:g} | {', '.join(f'{x:+.1f}' for x in c)} | {err:.2f} | "
                  f"{int(np.max(log[:, L.FAILSAFE]))} |", flush=True)


def main() -> None:
    if len(sys.argv) >= 2 and sys.argv[1] == "altitude":
        altitude([float(a) for a in sys.argv[2:]] or [0.0, 200.0])
    elif len(sys.argv) == 2 and sys.argv[1] == "faults":
        faults()
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
