"""What an experiment of the reproduction is, and what it hands to the report.

An experiment (one module per paper figure, listed in :mod:`gcs_tools.reproduce.experiments`)
provides

* ``NAME``, ``TITLE``, ``PAPER`` (where the paper shows it);
* ``jobs(ctx) -> list[SimJob]`` - its headless runs (:mod:`rig_emulator.sweep` runs them,
  all experiments' jobs together, in parallel);
* optionally ``live(ctx)`` - work that cannot be a headless job (the rectangle flown over
  MAVLink), run in the calling process;
* ``analyse(ctx, results, live) -> Section`` - numbers, figures (written to ``ctx.out_dir``)
  and a :class:`Verdict` per claim of the paper, computed from the results.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from gcs_tools.reproduce.paper_data import CLAIMS

REPRODUCED = "reproduced"
PARTLY = "partly reproduced"
NOT_REPRODUCED = "not reproduced"
NOT_RUN = "not run"
STATUSES = (REPRODUCED, PARTLY, NOT_REPRODUCED, NOT_RUN)


def status_letter(status: str) -> str:
    """A verdict as one letter of a per-seed list: y reproduced, p partly, n otherwise."""
    return {REPRODUCED: "y", PARTLY: "p"}.get(status, "n")


@dataclass(frozen=True)
class Context:
    """What every experiment's runs share: the seed, the plant (an airframe preset: ``hilms``
    the hardware rig, ``hilms-ideal`` the ideal plant) and parameter overrides on top of it
    (a reading of the readings table, docs/how-to/reproduce.md), as (key, value) pairs."""

    seed: int
    quick: bool
    out_dir: Path
    airframe: str = "hilms"
    overrides: tuple = ()

    def job(self, scenario: str, strategy: str, duration=None, overrides=None, columns=None, label: str = ""):
        """A :class:`~rig_emulator.sweep.SimJob` of this context's seed, plant and overrides
        (the experiment's own ``overrides`` win over the context's)."""
        from rig_emulator.sweep import SimJob

        merged = dict(self.overrides)
        merged.update(overrides or {})
        return SimJob(scenario, strategy, seed=self.seed, duration=duration, overrides=merged,
                      airframe=self.airframe, columns=columns, label=label)
    controller: str = ""  # controller plug-ins to compare (exp_controller), 'package.module:Name', comma-separated
    strategy: str = "smc-flc"  # the loops the plug-in keeps
    compare: tuple = ()  # with a controller: the experiments it flies (gcs_tools.reproduce.compare; () = all)


@dataclass(frozen=True)
class Verdict:
    """The emulation's answer to one claim of the paper (``claim`` is a key of ``paper_data.CLAIMS``)."""

    claim: str
    status: str
    evidence: str

    def __post_init__(self):
        if self.claim not in CLAIMS:
            raise ValueError(f"unknown claim {self.claim!r}")
        if self.status not in STATUSES:
            raise ValueError(f"status {self.status!r}: must be one of {STATUSES}")

    @property
    def text(self) -> str:
        return CLAIMS[self.claim][0]

    @property
    def source(self) -> str:
        return CLAIMS[self.claim][1]

    def line(self) -> str:
        return f"**{self.status}** - {self.text} ({self.source}): {self.evidence}"


@dataclass
class Section:
    """One experiment's part of the report."""

    name: str
    title: str
    paper: str
    body: str  # markdown: set-up, tables, notes (no heading)
    figures: list = field(default_factory=list)  # PNG file names in the output directory
    numbers: dict = field(default_factory=dict)  # JSON-able figures for results.json
    verdicts: list = field(default_factory=list)


def status_of(ok: bool) -> str:
    return REPRODUCED if ok else NOT_REPRODUCED


def fmt(x, digits: int = 3, unit: str = "") -> str:
    """A number for the report: fixed decimals, '-' for NaN/None, 'inf' kept readable."""
    if x is None:
        return "-"
    x = float(x)
    if math.isnan(x):
        return "-"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    s = f"{x:.{digits}f}"
    if s.startswith("-") and float(s) == 0.0:
        s = s[1:]
    return s + (f" {unit}" if unit else "")


def times(ours: float, paper: float) -> str:
    """'4.2x smaller than' / '1.3x larger than' / 'equal to': ours relative to the paper's."""
    if not (ours > 0 and paper > 0 and math.isfinite(ours) and math.isfinite(paper)):
        return "not comparable with"
    if ours == paper:
        return "equal to"
    return f"{paper / ours:.1f}x smaller than" if ours < paper else f"{ours / paper:.1f}x larger than"


def table(header: list, rows: list) -> str:
    """A markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def jsonable(x):
    """Numbers and containers for results.json: NaN -> None, +-inf -> 'inf' / '-inf'."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if hasattr(x, "tolist") and not isinstance(x, (str, bytes)):  # numpy arrays and scalars
        return jsonable(x.tolist())
    if isinstance(x, float):
        if math.isnan(x):
            return None
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
    return x
