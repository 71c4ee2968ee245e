"""Blind test of the regression identification (`rig-gcs identify --tlog`, method regression) on the default
`hilms` plant: every identifiable effect hidden at once at values drawn inside this test (seeded: the test
is deterministic), the identification flight (scenario sysid) flown with a noise seed of its own and
written as a .tlog, the effects recovered from the log alone with the hilms preset as the base (which
knows none of the drawn values), and checked against the truth: the error and whether the reported 95 %
interval holds it. The centre of gravity (3 axes) must be within 10 % of its range (its intervals are
still too narrow: a strict expected failure); the motor chain, the delay and the joint's
friction are a strict expected failure (they do not all pass yet: docs/how-to/identify.md); the random
torque's level is not checked (the calibration study shows it over-estimated).

Three draws cost about a minute of CPU (three 90 s flights at 20-30x real time, the .tlog export, three
fits of about 14 s). The calibration study (`rig-gcs identify --calibration-study N`) measures the same
over more draws; docs/how-to/identify.md has its table.
"""

import json

import numpy as np
import pytest

from gcs_tools.cli import main
from gcs_tools.identify.study import DRAW_RANGES, as_overrides
from rig_emulator.config.loader import load_config
from rig_emulator.link.telemetry.tlog_export import export_tlog
from rig_emulator.simulation.run import Simulation

N_DRAWS = 3
DRAW_SEED = 20261128  # the test's own draws, not the study's
LOG_SEED = 4100  # noise seeds of the flights: the fit never sees them
#: recovered blind: within WITHIN of the range, and the 95 % intervals hold the truth often enough
COG = [k for k in DRAW_RANGES if k.startswith("joint.cog_offset")]
#: not yet: the motor chain (where the motors run near the load cells' ceiling, the firmware's guards bias
#: the filtered readings), the delay's interval (too narrow), the friction (viscous and Coulomb trade off
#: where the swings are short); docs/how-to/identify.md, "How far to trust it"
REST = [k for k in DRAW_RANGES if k.startswith(("motors.", "control.", "joint.viscous", "joint.coulomb"))]
WITHIN = 0.10
COVERAGE = 0.85  # of the (parameter, draw) pairs whose 95 % interval holds the truth


@pytest.fixture(scope="module")
def blind_fits(tmp_path_factory):
    rng = np.random.default_rng(DRAW_SEED)
    out = []
    d = tmp_path_factory.mktemp("blind")
    for i in range(N_DRAWS):
        hidden = {k: float(rng.uniform(lo, hi)) for k, (lo, hi) in DRAW_RANGES.items()}
        cfg = load_config(airframe="hilms", scenario="sysid",
                          overrides={**as_overrides(hidden), "control.strategy": "flc", "sim.seed": LOG_SEED + i})
        log = d / f"draw{i}.tlog"
        export_tlog(Simulation(cfg).run(), log)
        js = d / f"draw{i}.json"
        assert main(["identify", "--tlog", str(log), "-o", str(d / f"draw{i}.toml"), "--json", str(js)]) == 0
        doc = json.loads(js.read_text())
        out.append((hidden, {e["key"]: e for e in doc["estimates"]}, doc))
        # the fitted preset loads as a --config file
        load_config(airframe="hilms", files=[str(d / f"draw{i}.toml")])
    return out


def _check(blind_fits, keys, coverage=True):
    inside, total, misses = 0, 0, []
    for hidden, est, _ in blind_fits:
        for key in keys:
            lo, hi = DRAW_RANGES[key]
            e = est[key]
            assert abs(e["value"] - hidden[key]) <= WITHIN * (hi - lo), (key, e["value"], hidden[key])
            total += 1
            if e["lo"] <= hidden[key] <= e["hi"]:
                inside += 1
            else:
                misses.append((key, hidden[key], e["lo"], e["hi"]))
    if coverage:
        assert inside / total >= COVERAGE, misses


def test_centre_of_gravity_recovered_blind(blind_fits):
    _check(blind_fits, COG, coverage=False)


@pytest.mark.xfail(strict=True, reason="the centre of gravity's intervals are too narrow: the attitude estimate's "
                                       "error is not in them (docs/how-to/identify.md)")
def test_centre_of_gravity_inside_its_intervals(blind_fits):
    _check(blind_fits, COG)


@pytest.mark.xfail(strict=True, reason="motor chain biased near the thrust ceiling, delay and friction intervals "
                                       "too narrow (docs/how-to/identify.md)")
def test_motor_chain_delay_and_friction_recovered_blind_within_their_intervals(blind_fits):
    _check(blind_fits, REST)
