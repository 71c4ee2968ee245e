"""The report's account of what the `hilms` preset was fitted against, and how it does on what it did not see.

* :func:`intro` - the report's opening sentence on tuning, from ``gcs_tools/identify/hilms_sources.toml``:
  which values were fitted against which of the paper's numbers, how many were set by hand
  against them;
* :func:`section` - every one of the paper's 18 numbers and 16 claims marked **fitted**, **set by hand
  against** (with the keys) or **predicted** (:func:`gcs_tools.identify.provenance.marks`), then
  the leave-one-group-out table of ``HELD_OUT_FILE`` (written by ``rig-gcs identify --paper
  --held-out logo``; :mod:`gcs_tools.identify.held_out`).

Both depend on shipped files only, so the report stays a function of the runs and the installation.
"""

from __future__ import annotations

import json
from importlib import resources

from gcs_tools.identify import provenance
from gcs_tools.reproduce.experiment import table

#: the shipped leave-one-group-out table (gcs_tools/identify/), its command inside
HELD_OUT_FILE = "held_out_hilms.json"
HARDWARE_PLANT = "hilms"


def section_applies(plants) -> bool:
    """The marks concern the `hilms` preset: shown when it is among the plants (None: the default, `hilms`)."""
    return plants is None or HARDWARE_PLANT in plants


def intro(plants) -> str:
    """The sentence on tuning: exact for the `hilms` plant, and that the ideal plant took nothing from the numbers."""
    if not section_applies(plants):
        return ("The plants of this report take Table 2 and the paper's controllers and were not set against these "
                "numbers: where the emulation disagrees, this report says so.")
    return provenance.summary_sentence() + " Where the emulation disagrees, this report says so."


def held_out_document() -> dict | None:
    node = resources.files("gcs_tools.identify") / HELD_OUT_FILE
    if not node.is_file():
        return None
    return json.loads(node.read_text(encoding="utf-8"))


def section(plants) -> str | None:
    """The markdown of the section (no heading), or None when `hilms` is not among the plants."""
    if not section_applies(plants):
        return None
    from gcs_tools.identify.paper import load_data
    from gcs_tools.reproduce.paper_data import CLAIMS

    marks = provenance.marks()
    c = provenance.counts(marks)
    targets, _ = load_data()
    lines = ["Which of the paper's numbers and claims a value of the `hilms` preset was fitted to (`rig-gcs identify "
             "--paper`), set by hand against (looked at while choosing it), or not looked at (**predicted**). Only "
             "predicted ones, and the held-out table below, test the model; the sources of every value are in "
             "`rig_emulator/presets/hardware/hilms.toml` and `gcs_tools/identify/hilms_sources.toml`.", "",
             f"Numbers: {c['numbers'][provenance.FITTED]} fitted, {c['numbers'][provenance.CHOSEN]} set by hand "
             f"against, {c['numbers'][provenance.PREDICTED]} predicted. Claims: {c['claims'][provenance.FITTED]} "
             f"fitted, {c['claims'][provenance.CHOSEN]} set by hand against, {c['claims'][provenance.PREDICTED]} "
             "predicted.", ""]
    rows = [[f"{t.source.split(':')[0]}: `{t.metric}`", f"{t.value:g} {t.unit}", marks[t.metric].text()]
            for t in targets]
    rows += [[f"{text} ({where})", "claim", marks[provenance.CLAIM_PREFIX + cid].text()]
             for cid, (text, where) in CLAIMS.items()]
    lines.append(table(["the paper's", "value", "`hilms` preset"], rows))
    doc = held_out_document()
    lines += ["", "### Held out: each group of numbers predicted by a fit on the others", ""]
    if doc is None:
        lines.append(f"No table shipped (`gcs_tools/identify/{HELD_OUT_FILE}`); `rig-gcs identify --paper --held-out "
                     "logo ... -o held.json` writes one (docs/explanation/paper-fit.md).")
    else:
        from gcs_tools.identify.held_out import markdown

        lines.append(markdown(doc, doc.get("command")))
    return "\n".join(lines)


def marks_json() -> dict:
    """For results.json: name -> {status, keys}."""
    return {n: {"status": m.status, "fitted": list(m.keys), "set_by_hand": list(m.hand)}
            for n, m in provenance.marks().items()}
