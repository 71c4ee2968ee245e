"""The parameters an identification fits: keys, bounds, start values and priors.

A parameter is addressed the way ``--set KEY=VALUE`` addresses configuration, plus an
element where a key holds several numbers:

* ``motors.time_constant`` - a numeric key of :data:`rig_emulator.config.schema.SCHEMA`;
* ``smc.k[0]`` - one element of a list key (``vec3`` / ``floats``); ``smc.k[0,1]`` - several
  elements tied to one fitted value (e.g. the roll and pitch gains alike);
* ``disturbance.extra_masses[1].mass`` - one numeric field of one entry of a list of tables;
* ``sensor_models.mpu6050.gyro.noise_density`` - a leaf of a sensor-model tree.

Every bound is validated against the key's own range (:func:`rig_emulator.config.loader.check_value`),
so a fit can never propose a value the loader would refuse. Integer, string and boolean keys
are refused: the optimiser works on continuous values.

From the command line (``--params``)::

    KEY=LO:HI[:START][,KEY=LO:HI...]          --prior KEY=MEAN+-SIGMA

or a spec file (``--spec fit.toml``)::

    [[param]]
    key = "motors.time_constant"
    lo = 0.02
    hi = 0.1
    start = 0.05          # optional: default the configured value (mid-range when outside the bounds)
    prior = [0.05, 0.01]  # optional Gaussian prior: mean, sigma
    step = 0.001          # optional: smallest finite-difference step in the key's unit (``--step KEY=STEP``),
                          # for a key the rig quantises (``control.actuation_delay``: whole physics steps)
"""

from __future__ import annotations

import copy
import difflib
import math
import re
from dataclasses import dataclass
from typing import Any, Mapping

from rig_emulator.config.loader import ConfigError, check_value
from rig_emulator.config.schema import SCHEMA, Spec

_KEY = re.compile(r"^(?P<base>[A-Za-z0-9_.]+?)(?:\[(?P<index>\d+(?:,\d+)*)\](?:\.(?P<field>[A-Za-z0-9_]+))?)?$")


@dataclass(frozen=True)
class ParamKey:
    """Where a fitted number lives in a configuration (see the module docstring)."""

    text: str  # as the user wrote it, canonical (``smc.k[0]``)
    base: str  # the schema key
    kind: str  # "scalar", "element", "table_field" or "tree_leaf"
    index: int | None = None  # the entry of a list of tables
    elements: tuple = ()  # the elements of a list key set to the fitted value
    field: str | None = None  # table field
    path: tuple = ()  # tree leaf path below the schema key
    spec: Spec | None = None  # the spec a single value is checked against (None for tree leaves)

    def check(self, value: float, label: str) -> float:
        """``value`` validated as this key's value (ConfigError naming ``label`` and the range)."""
        if self.kind == "tree_leaf":
            tree: dict = {}
            node = tree
            for part in self.path[:-1]:
                node = node.setdefault(part, {})
            node[self.path[-1]] = float(value)
            try:
                check_value(self.base, SCHEMA[self.base], tree)
            except ConfigError as exc:
                raise ConfigError(f"{label}: {exc}") from None
            return float(value)
        try:
            return check_value(self.text, self.spec, float(value))
        except ConfigError as exc:
            raise ConfigError(f"{label}: {exc}") from None

    def get(self, cfg: Mapping[str, Any]) -> float:
        """This key's value in a validated configuration."""
        v = cfg[self.base]
        try:
            if self.kind == "scalar":
                return float(v)
            if self.kind == "element":
                return float(v[self.elements[0]])
            if self.kind == "table_field":
                return float(v[self.index][self.field])
            node = v
            for part in self.path:
                node = node[part]
            return float(node)
        except (IndexError, KeyError, TypeError) as exc:
            raise ConfigError(f"{self.text}: not in this configuration ({type(exc).__name__}: {exc})") from None

    def put(self, cfg: Mapping[str, Any], overrides: dict, value: float) -> None:
        """Set this key to ``value`` in ``overrides`` (whole-key overrides, built on ``cfg``'s values
        and on what ``overrides`` already holds for the same key)."""
        if self.kind == "scalar":
            overrides[self.base] = float(value)
            return
        current = overrides[self.base] if self.base in overrides else copy.deepcopy(cfg[self.base])
        if self.kind == "element":
            if not isinstance(current, list) or max(self.elements) >= len(current):
                raise ConfigError(f"{self.text}: {self.base} has {len(current) if isinstance(current, list) else 0} "
                                  f"numbers in this configuration, no element {max(self.elements)}")
            for i in self.elements:
                current[i] = float(value)
        elif self.kind == "table_field":
            if not isinstance(current, list) or self.index >= len(current):
                raise ConfigError(f"{self.text}: {self.base} has {len(current) if isinstance(current, list) else 0} "
                                  f"entries in this configuration, no entry {self.index}")
            current[self.index] = dict(current[self.index])
            current[self.index][self.field] = float(value)
        else:
            node = current
            for part in self.path[:-1]:
                node = node.setdefault(part, {})
            node[self.path[-1]] = float(value)
        overrides[self.base] = current


def _unknown(key: str) -> ConfigError:
    hint = difflib.get_close_matches(key, SCHEMA.keys(), n=1)
    return ConfigError(f"unknown parameter {key!r}" + (f" (did you mean {hint[0]!r}?)" if hint else ""))


def _element_spec(spec: Spec) -> Spec:
    return Spec("float", spec.doc, spec.unit, spec.lo, spec.hi, spec.lo_open)


def parse_key(text: str) -> ParamKey:
    """A :class:`ParamKey` for ``text`` (ConfigError naming it when it is not a fittable number)."""
    text = text.strip()
    m = _KEY.match(text)
    if not m:
        raise ConfigError(f"parameter {text!r}: expected KEY, KEY[i] or KEY[i].FIELD")
    base, index, fld = m.group("base"), m.group("index"), m.group("field")
    if index is not None:
        elements = tuple(int(i) for i in index.split(","))
        if len(set(elements)) != len(elements):
            raise ConfigError(f"parameter {text!r}: an element is named twice")
    if base not in SCHEMA:
        # a leaf of a sensor-model tree: the longest schema prefix of kind "tree"
        parts = base.split(".")
        for cut in range(len(parts) - 1, 0, -1):
            head = ".".join(parts[:cut])
            if head in SCHEMA and SCHEMA[head].kind == "tree":
                if index is not None:
                    raise ConfigError(f"parameter {text!r}: list elements of sensor-model trees cannot be fitted")
                return ParamKey(text, head, "tree_leaf", path=tuple(parts[cut:]))
        raise _unknown(base)
    spec = SCHEMA[base]
    if spec.kind == "float":
        if index is not None:
            raise ConfigError(f"parameter {text!r}: {base} holds one number (write {base})")
        return ParamKey(text, base, "scalar", spec=spec)
    if spec.kind in ("vec3", "floats"):
        if index is None or fld is not None:
            raise ConfigError(f"parameter {text!r}: {base} is a list; fit one element, e.g. {base}[0]")
        if spec.length is not None and max(elements) >= spec.length:
            raise ConfigError(f"parameter {text!r}: {base} has {spec.length} elements (index 0..{spec.length - 1})")
        return ParamKey(text, base, "element", elements=elements, spec=_element_spec(spec))
    if spec.kind == "table_list":
        if index is None or fld is None:
            raise ConfigError(f"parameter {text!r}: {base} is a list of tables; fit one field, e.g. {base}[0].FIELD")
        if fld not in spec.item:
            raise ConfigError(f"parameter {text!r}: {base} entries have the fields {', '.join(spec.item)}")
        item = spec.item[fld]
        if item.kind != "float":
            raise ConfigError(f"parameter {text!r}: {base}[].{fld} is not a continuous number ({item.kind})")
        if len(elements) != 1:
            raise ConfigError(f"parameter {text!r}: name one entry of {base}, e.g. {base}[0].{fld}")
        return ParamKey(text, base, "table_field", index=elements[0], field=fld, spec=item)
    if spec.kind == "int":
        raise ConfigError(f"parameter {text!r}: an integer parameter; identify fits continuous numbers only")
    if spec.kind == "tree":
        raise ConfigError(f"parameter {text!r}: a sensor-model tree; fit one of its numbers, e.g. {base}.SECTION.NAME")
    raise ConfigError(f"parameter {text!r}: a {spec.kind} parameter, not a number")


@dataclass(frozen=True)
class Param:
    """A fitted parameter: key, bounds, optional start value and Gaussian prior."""

    key: ParamKey
    lo: float
    hi: float
    start: float | None = None
    prior: tuple | None = None  # (mean, sigma)
    step: float | None = None  # smallest finite-difference step, own unit (a quantised key: its quantum)

    @property
    def name(self) -> str:
        return self.key.text

    def to_unit(self, value: float) -> float:
        """Physical value -> [0, 1] across the bounds (what the optimiser moves)."""
        return (value - self.lo) / (self.hi - self.lo)

    def from_unit(self, z: float) -> float:
        z = min(max(float(z), 0.0), 1.0)
        return self.lo + z * (self.hi - self.lo)

    def describe(self) -> dict:
        d = {"key": self.name, "lo": self.lo, "hi": self.hi}
        if self.start is not None:
            d["start"] = self.start
        if self.prior is not None:
            d["prior"] = list(self.prior)
        if self.step is not None:
            d["step"] = self.step
        return d


def _number(text: Any, what: str) -> float:
    if isinstance(text, bool):
        raise ConfigError(f"{what} {text!r}: not a number")
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} {text!r}: not a number") from None
    if not math.isfinite(v):
        raise ConfigError(f"{what} {text!r}: must be finite")
    return v


def make_param(key: str, lo: Any, hi: Any, start: Any = None, prior: Any = None, where: str = "",
               step: Any = None) -> Param:
    """A validated :class:`Param` (ConfigError naming ``where`` and the key otherwise)."""
    label = f"{where}{key}" if where else key
    try:
        pk = parse_key(key)
    except ConfigError as exc:
        raise ConfigError(f"{where}{exc}" if where else str(exc)) from None
    lo_v, hi_v = _number(lo, f"{label}: lower bound"), _number(hi, f"{label}: upper bound")
    if not lo_v < hi_v:
        raise ConfigError(f"{label}: lower bound {lo_v:g} must be below the upper bound {hi_v:g}")
    pk.check(lo_v, f"{label}: lower bound")
    pk.check(hi_v, f"{label}: upper bound")
    spec = pk.spec
    if spec is not None and spec.gap_to is not None and lo_v < spec.gap_to and hi_v > spec.lo:
        # a fit must not propose a value inside the key's refused hole
        raise ConfigError(f"{label}: bounds [{lo_v:g}, {hi_v:g}] meet the refused interval ({spec.lo:g}, "
                          f"{spec.gap_to:g}) ({pk.base} must be {spec.describe_gap()}); fit within [{spec.gap_to:g}, ...]")
    st = None
    if start is not None:
        st = _number(start, f"{label}: start")
        if not lo_v <= st <= hi_v:
            raise ConfigError(f"{label}: start {st:g} is outside the bounds [{lo_v:g}, {hi_v:g}]")
    pr = None
    if prior is not None:
        if not isinstance(prior, (list, tuple)) or len(prior) != 2:
            raise ConfigError(f"{label}: prior must be [mean, sigma]")
        mean, sigma = _number(prior[0], f"{label}: prior mean"), _number(prior[1], f"{label}: prior sigma")
        if not sigma > 0:
            raise ConfigError(f"{label}: prior sigma {sigma:g} must be > 0")
        pr = (mean, sigma)
    sp = None
    if step is not None:
        sp = _number(step, f"{label}: step")
        if not 0 < sp <= 0.5 * (hi_v - lo_v):
            raise ConfigError(f"{label}: step {sp:g} must be > 0 and at most half the range ({0.5 * (hi_v - lo_v):g})")
    return Param(pk, lo_v, hi_v, st, pr, sp)


def parse_params_arg(text: str) -> list[Param]:
    """``KEY=LO:HI[:START][,KEY=LO:HI...]`` (the ``--params`` option)."""
    out = []
    for item in (s.strip() for s in re.split(r",(?![^\[]*\])", text)):  # commas outside [..]
        if not item:
            continue
        if "=" not in item:
            raise ConfigError(f"--params {item!r}: expected KEY=LO:HI")
        key, rng = (s.strip() for s in item.split("=", 1))
        parts = rng.split(":")
        if len(parts) not in (2, 3):
            raise ConfigError(f"--params {item!r}: expected KEY=LO:HI or KEY=LO:HI:START")
        out.append(make_param(key, parts[0], parts[1], parts[2] if len(parts) == 3 else None, where="--params "))
    return out


def parse_prior_arg(text: str) -> tuple[str, tuple]:
    """``KEY=MEAN+-SIGMA`` (the ``--prior`` option) -> (key, (mean, sigma))."""
    if "=" not in text or "+-" not in text:
        raise ConfigError(f"--prior {text!r}: expected KEY=MEAN+-SIGMA")
    key, rest = (s.strip() for s in text.split("=", 1))
    mean, sigma = rest.split("+-", 1)
    return key, (_number(mean, f"--prior {key}: mean"), _number(sigma, f"--prior {key}: sigma"))


def params_from_spec(doc: Mapping, where: str) -> list[Param]:
    """The ``[[param]]`` tables of a spec file."""
    items = doc.get("param", [])
    if not isinstance(items, list) or not all(isinstance(p, Mapping) for p in items):
        raise ConfigError(f"{where}: 'param' must be a list of tables ([[param]])")
    out = []
    for i, p in enumerate(items):
        unknown = set(p) - {"key", "lo", "hi", "start", "prior", "step"}
        if unknown:
            raise ConfigError(f"{where}: param[{i}]: unknown field(s) {sorted(unknown)}; allowed: key, lo, hi, start, "
                              "prior, step")
        for need in ("key", "lo", "hi"):
            if need not in p:
                raise ConfigError(f"{where}: param[{i}]: missing {need!r}")
        if not isinstance(p["key"], str):
            raise ConfigError(f"{where}: param[{i}].key must be a string")
        out.append(make_param(p["key"], p["lo"], p["hi"], p.get("start"), p.get("prior"), where=f"{where}: ",
                              step=p.get("step")))
    return out


def merge(params: list[Param], priors: dict, steps: dict | None = None) -> list[Param]:
    """``params`` with the ``--prior`` priors and ``--step`` steps attached; ConfigError for a
    duplicate key, or a prior or step on a key that is not fitted."""
    steps = steps or {}
    seen = set()
    for p in params:
        if p.name in seen:
            raise ConfigError(f"parameter {p.name!r} is given twice")
        seen.add(p.name)
    for opt, given in (("--prior", priors), ("--step", steps)):
        for k in given:
            if k not in seen:
                raise ConfigError(f"{opt} {k}: not among the fitted parameters ({', '.join(sorted(seen)) or 'none'})")
    out = []
    for p in params:
        if p.name in priors or p.name in steps:
            p = make_param(p.name, p.lo, p.hi, p.start, priors.get(p.name, p.prior), step=steps.get(p.name, p.step))
        out.append(p)
    return out


def parse_step_arg(text: str) -> tuple[str, float]:
    """``KEY=STEP`` (the ``--step`` option) -> (key, step in the key's unit)."""
    if "=" not in text:
        raise ConfigError(f"--step {text!r}: expected KEY=STEP")
    key, v = (s.strip() for s in text.split("=", 1))
    return key, _number(v, f"--step {key}")


def start_values(params: list[Param], cfg: Mapping[str, Any]) -> list[float]:
    """Each parameter's start: its ``start``, else its value in ``cfg`` when inside the bounds,
    else the middle of the bounds."""
    out = []
    for p in params:
        if p.start is not None:
            out.append(p.start)
            continue
        try:
            v = p.key.get(cfg)
        except ConfigError:
            v = math.nan
        out.append(v if p.lo <= v <= p.hi else 0.5 * (p.lo + p.hi))
    return out


def overrides_for(params: list[Param], values: list[float], cfg: Mapping[str, Any]) -> dict:
    """Whole-key overrides that set every parameter to its value on top of ``cfg``."""
    out: dict = {}
    for p, v in zip(params, values):
        p.key.put(cfg, out, v)
    return out
