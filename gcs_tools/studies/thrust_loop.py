"""The load-cell thrust loop's study (docs/explanation/readings.md, "The motor voltages: a load-cell
thrust loop"): Fig. 17's altitude error early vs late per time constant and seed, and what a
faulted load cell does to it.

    python -m gcs_tools.studies thrust-loop altitude 0 5 20 60 100 200 500 1000
    python -m gcs_tools.studies thrust-loop faults
    python -m gcs_tools.studies thrust-loop altitude 0 20 200 1000 --markdown FILE   # also write the table

``--markdown FILE`` writes the table as a page for the docs, with the command and the machine.

The claim verdicts and the Table 4 / Table 6 / Fig. 19 numbers per time constant come from
``rig-gcs reproduce -o DIR --plant hilms --seeds 3 --set motors.thrust_loop_time_constant=T``.
"""

import argparse
import sys

import numpy as np

from rig_emulator.api import simulate
from rig_emulator.config.loader import load_config
from rig_emulator.control.controller import CS_THRUST_CORR
from rig_emulator.physics.motors import GRAM_FORCE_N
from rig_emulator.simulation import log_layout as L
from rig_emulator.simulation.run import Simulation

from gcs_tools.studies.page import Page


def _me(t, z, zd, a, b):
    m = (t >= a) & (t <= b)
    return float(np.mean(np.abs(zd[m] - z[m])))


def altitude(tcs, out: Page):
    """ME Z of the rig's own altitude over 30-60 s and 200-250 s of the 250 s helix, IIR, seeds 0-2."""
    out.print("| T (s) | strategy | seed | ME Z 30-60 s (mm) | ME Z 200-250 s (mm) | late - early (mm) |")
    out.print("|---|---|---|---|---|---|")
    for tc in tcs:
        for s in ("smc-flc", "flc"):
            for seed in (0, 1, 2):
                log = simulate("helix", s, duration=250.0, seed=seed,
                               overrides={"motors.thrust_loop_time_constant": tc,
                                          "estimation.load_cell_filter": "iir"}).log
                t, z, zd = log[:, L.T], log[:, L.POS + 2], log[:, L.POS_DES + 2]
                e, late = _me(t, z, zd, 30.0, 60.0), _me(t, z, zd, 200.0, 250.0)
                out.print(f"| {tc:g} | {s} | {seed} | {e * 1e3:.1f} | {late * 1e3:.1f} | {(late - e) * 1e3:+.1f} |")


def faults(out: Page):
    """Hover 60 s, smc-flc, seed 0, load cell 2 dead or stuck from 5 s: the corrections and the attitude."""
    out.print("| fault (t = 5 s, cell 2) | T (s) | corrections at 60 s (gr.F, motors 1-4) | "
              "max abs roll/pitch error 10-60 s (deg) | failsafe |")
    out.print("|---|---|---|---|---|")
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
            out.print(f"| {mode} | {tc:g} | {', '.join(f'{x:+.1f}' for x in c)} | {err:.2f} | "
                      f"{int(np.max(log[:, L.FAILSAFE]))} |")


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gcs_tools.studies thrust-loop", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", choices=("altitude", "faults"))
    ap.add_argument("time_constants", nargs="*", type=float, metavar="T",
                    help="altitude: the thrust loop's time constants (s); default 0 200")
    ap.add_argument("--markdown", metavar="FILE", help="also write the table to FILE, with the command and the machine")
    return ap


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        sys.exit(__doc__)
    a = parser().parse_args(argv)
    if a.study == "faults" and a.time_constants:
        parser().error("faults takes no time constants")
    if a.study == "altitude":
        out = Page(a.markdown, "The rig's own altitude error on the 250 s helix (Figs. 16-17), `hilms`, "
                               "load-cell filter IIR, per time constant T of the thrust loop, strategy and seed; "
                               "runs in the calling process.")
        altitude(a.time_constants or [0.0, 200.0], out)
    else:
        out = Page(a.markdown, "Hover for 60 s on `hilms`, smc-flc, seed 0, load cell 2 dead or stuck from "
                               "t = 5 s: the thrust loop's corrections at the end and the attitude error; runs "
                               "in the calling process.")
        faults(out)
    out.write()


if __name__ == "__main__":
    main()
