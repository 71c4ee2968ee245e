"""The reproduction report says exactly what the `hilms` preset was fitted against: its opening
sentence names the fitted keys and their numbers, a section marks each of the 18 numbers and 16
claims, and a report of the ideal plant alone does not claim a fit it did not have. No runs: the
report is rendered from no sections."""

import json

from gcs_tools.identify import provenance
from gcs_tools.reproduce import paper_fit_section
from gcs_tools.reproduce.plants import PlantRuns
from gcs_tools.reproduce.report import render, results_document
from gcs_tools.reproduce.paper_data import CLAIMS


def _column(plant):
    return PlantRuns(plant, plant, (), {0: []})


def test_the_report_names_what_was_fitted_to_what():
    md = render([], None, seed=0, quick=True, columns=[_column("hilms"), _column("hilms-ideal")])
    assert "not tuned" not in md
    for s in provenance.fitted_keys():
        assert f"`{s.key}` fitted to {', '.join(s.fitted)}" in md
    section = md.split("## What the `hilms` preset was fitted against")[1]
    marks = provenance.marks()
    for name, m in marks.items():
        if not name.startswith(provenance.CLAIM_PREFIX):
            assert f"`{name}`" in section
    for text, _ in CLAIMS.values():
        assert text in section
    assert section.count("| fitted: ") + section.count("| set by hand against: ") + section.count(
        "| **predicted** |") == 18 + len(CLAIMS)
    assert "### Held out" in section
    doc = json.loads(results_document([], None, 0, True, columns=[_column("hilms")]))
    assert doc["paper_fit_marks"]["table4.smc.phi_deg"]["fitted"] == ["control.actuation_delay"]


def test_an_ideal_plant_report_claims_no_fit():
    md = render([], None, seed=0, quick=True, columns=[_column("hilms-ideal")])
    assert "were not set against these numbers" in md
    assert "What the `hilms` preset was fitted against" not in md
    assert paper_fit_section.section(["hilms-ideal"]) is None
    doc = json.loads(results_document([], None, 0, True, columns=[_column("hilms-ideal")]))
    assert "paper_fit_marks" not in doc
