"""scripts/docs_gen.py --refit: the paper fit's refit table (docs/explanation/paper-fit.md includes
docs/generated/paper-refit.md) from the --json file of `rig-gcs identify --paper`, here from a made-up
one: each key's start and fitted value in the schema's unit (delays in ms), its sigma, its prior, a
value at a bound said so, and the command and the fit's cost of time on the page."""

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("docs_gen", ROOT / "scripts" / "docs_gen.py")
docs_gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(docs_gen)


def test_the_refit_page_gives_each_key_in_its_unit_with_sigma_and_prior(tmp_path):
    doc = {"command": "rig-gcs identify --paper --json refit.json", "status": "converged", "evaluations": 12,
           "runs": 408, "wall_s": 61.4,
           "params": [{"key": "control.actuation_delay", "value": 0.0122237, "sigma": 0.0011, "start": 0.013,
                       "at_bound": False, "prior": None},
                      {"key": "joint.coulomb[0,1]", "value": 0.00782301, "sigma": 0.0074, "start": 0.05,
                       "at_bound": False, "prior": [0.0, 0.01]},
                      {"key": "flc.position_rate_share", "value": 1.0, "sigma": 0.2, "start": 0.46,
                       "at_bound": True, "prior": None}]}
    path = tmp_path / "refit.json"
    path.write_text(json.dumps(doc))
    page = docs_gen.refit_page(path, "a test machine")
    head, table = page.split("\n\n", 1)
    assert "`rig-gcs identify --paper --json refit.json`" in head
    assert "12 points, 408 headless runs, 61 s wall on a test machine; fit status: converged" in head
    assert table.splitlines()[2:] == [
        "| `control.actuation_delay` | 13 ms | 12.2 +- 1.1 ms | - |",
        "| `joint.coulomb[0,1]` | 0.05 N m | 0.00782 +- 0.0074 N m | 0 +- 0.01 N m |",
        "| `flc.position_rate_share` | 0.46 | 1 +- 0.2 (at a bound) | - |",
    ]
