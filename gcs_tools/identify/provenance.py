"""Where the `hilms` plant's values come from, and which of the paper's numbers they were set against.

``hilms_sources.toml`` lists every value of the `hilms` plant (the airframe of Table 2 in
``presets/airframes/hilms-ideal.toml`` and the hardware of ``presets/hardware/hilms.toml``) with its
kind (paper, datasheet, fitted, chosen), its source, and the paper's numbers and claims it was
fitted or hand-set against. From it :func:`marks` says, for each of the paper's 18 numbers
(``gcs_tools/identify/paper_targets.toml``) and 16 claims (``gcs_tools/reproduce/paper_data.py``),
whether the shipped preset was **fitted** against it, **set by hand against** it, or whether
the emulator's value for it is a **prediction** (no value of the preset looked at it).

A number a value was fitted against agrees with the paper partly because of that fit: only
predicted numbers, and the held-out figures of ``rig-gcs identify --paper --held-out``
(:mod:`gcs_tools.identify.held_out`), test the model.
"""

from __future__ import annotations

import fnmatch
import tomllib
from dataclasses import dataclass
from importlib import resources

SOURCES_FILE = "hilms_sources.toml"
KINDS = ("paper", "datasheet", "fitted", "chosen")
FITTED = "fitted"
CHOSEN = "set by hand against"
PREDICTED = "predicted"
CLAIM_PREFIX = "claim:"


@dataclass(frozen=True)
class Source:
    """One value of the preset: its key, kind, source text, and what it was set against."""

    key: str
    kind: str
    source: str
    command: str = ""
    fitted: tuple = ()  # patterns of the paper's numbers / claims a fit used
    chosen: tuple = ()  # patterns of the paper's numbers / claims a hand choice looked at


@dataclass(frozen=True)
class Mark:
    """How one of the paper's numbers or claims relates to the shipped preset."""

    name: str  # a metric of paper_targets.toml, or claim:ID
    status: str  # FITTED, CHOSEN or PREDICTED
    keys: tuple  # the keys fitted against it
    hand: tuple = ()  # the keys set by hand against it (besides the fitted ones)

    def text(self) -> str:
        parts = []
        if self.keys:
            parts.append(f"{FITTED}: {', '.join(f'`{k}`' for k in self.keys)}")
        if self.hand:
            parts.append(f"{CHOSEN}: {', '.join(f'`{k}`' for k in self.hand)}")
        return "; ".join(parts) if parts else f"**{PREDICTED}**"


def load_sources(text: str | None = None) -> list[Source]:
    """The values of the shipped sources file (or of ``text``); ValueError naming a bad entry."""
    if text is None:
        text = (resources.files("gcs_tools.identify") / SOURCES_FILE).read_text(encoding="utf-8")
    out = []
    for i, v in enumerate(tomllib.loads(text).get("value", [])):
        for need in ("key", "kind", "source"):
            if need not in v:
                raise ValueError(f"{SOURCES_FILE}: value[{i}] has no {need!r}")
        if v["kind"] not in KINDS:
            raise ValueError(f"{SOURCES_FILE}: {v['key']}: kind {v['kind']!r} is not one of {KINDS}")
        if v["kind"] == "fitted" and not (v.get("command") and v.get("fitted")):
            raise ValueError(f"{SOURCES_FILE}: {v['key']}: a fitted value needs its command and what it was fitted to")
        if v["kind"] != "fitted" and v.get("fitted"):
            raise ValueError(f"{SOURCES_FILE}: {v['key']}: 'fitted' on a value of kind {v['kind']!r}")
        out.append(Source(v["key"], v["kind"], v["source"], v.get("command", ""), tuple(v.get("fitted", ())),
                          tuple(v.get("chosen", ()))))
    keys = [s.key for s in out]
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise ValueError(f"{SOURCES_FILE}: listed twice: {', '.join(dup)}")
    return out


def names() -> list[str]:
    """The paper's 18 numbers (metric names) then its 16 claims (``claim:ID``), in their files' order."""
    from gcs_tools.identify.paper import load_data
    from gcs_tools.reproduce.paper_data import CLAIMS

    targets, _ = load_data()
    return [t.metric for t in targets] + [CLAIM_PREFIX + c for c in CLAIMS]


def _matches(name: str, patterns) -> bool:
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


def marks(sources: list[Source] | None = None) -> dict[str, Mark]:
    """name -> :class:`Mark` for every number and claim of :func:`names`."""
    sources = load_sources() if sources is None else sources
    out = {}
    for name in names():
        fitted = tuple(s.key for s in sources if _matches(name, s.fitted))
        chosen = tuple(s.key for s in sources if _matches(name, s.chosen) and s.key not in fitted)
        status = FITTED if fitted else CHOSEN if chosen else PREDICTED
        out[name] = Mark(name, status, fitted, chosen)
    return out


def unmatched_patterns(sources: list[Source] | None = None) -> list[str]:
    """Patterns of the sources file that match no number or claim (a typo), as ``key: pattern``."""
    sources = load_sources() if sources is None else sources
    all_names = names()
    return [f"{s.key}: {p}" for s in sources for p in (*s.fitted, *s.chosen)
            if not any(fnmatch.fnmatchcase(n, p) for n in all_names)]


def fitted_keys(sources: list[Source] | None = None) -> list[Source]:
    """The values the shipped preset took from ``rig-gcs identify --paper`` fits."""
    sources = load_sources() if sources is None else sources
    return [s for s in sources if s.kind == "fitted"]


def counts(mark_map: dict[str, Mark]) -> dict:
    """How many numbers and claims carry each status: {"numbers": {...}, "claims": {...}}."""
    out = {"numbers": {FITTED: 0, CHOSEN: 0, PREDICTED: 0}, "claims": {FITTED: 0, CHOSEN: 0, PREDICTED: 0}}
    for name, m in mark_map.items():
        out["claims" if name.startswith(CLAIM_PREFIX) else "numbers"][m.status] += 1
    return out


def summary_sentence(mark_map: dict[str, Mark] | None = None) -> str:
    """One sentence for the report: which values were fitted against which of the paper's numbers."""
    sources = load_sources()
    mark_map = marks(sources) if mark_map is None else mark_map
    fitted = "; ".join(f"`{s.key}` fitted to {', '.join(s.fitted)}" for s in fitted_keys(sources))
    hand = [s.key for s in sources if s.kind == "chosen" and s.chosen]
    c = counts(mark_map)
    return (f"The `hilms` plant is not independent of these numbers: {fitted} (`rig-gcs identify --paper`), and "
            f"{len(hand)} more values were set by hand while looking at them ({', '.join(f'`{k}`' for k in hand)}). "
            f"Of the 18 numbers {c['numbers'][FITTED]} were fitted against, {c['numbers'][CHOSEN]} set by hand "
            f"against, {c['numbers'][PREDICTED]} predicted; of the 16 claims {c['claims'][FITTED]} fitted against, "
            f"{c['claims'][CHOSEN]} set by hand against (the count of claims reproduced was one criterion), "
            f"{c['claims'][PREDICTED]} predicted (`gcs_tools/identify/hilms_sources.toml`). The ideal plant "
            "`hilms-ideal` takes only Table 2 and the paper's controllers and was not set against them.")
