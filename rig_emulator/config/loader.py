"""Load, merge and validate rig parameter files (TOML presets + user files + overrides).

Layers, later ones winning: ``presets/rig.toml`` (every default), the hardware preset an
airframe selects (``presets/hardware/<name>.toml``: the real rig's effects and readings,
``hilms`` selects one, ``hilms-ideal`` none), an airframe preset
(``presets/airframes/<name>.toml``, Table 2), a scenario preset
(``presets/scenarios/<name>.toml``), user TOML files, then dotted-key overrides such as
``{"smc.switching": "boundary"}``. Every leaf is checked against
:data:`rig_emulator.config.schema.SCHEMA`; an error names the key, the value and the
allowed range.
"""

from __future__ import annotations

import copy
import difflib
import functools
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any, Iterable, Mapping

from rig_emulator.config.schema import SCHEMA, Spec
from rig_emulator.fast_copy import fast_deepcopy


class ConfigError(ValueError):
    """A parameter is missing, unknown, of the wrong type or out of range."""


def _preset_dir(kind: str | None = None):
    root = resources.files("rig_emulator") / "presets"
    return root / kind if kind else root


def available(kind: str) -> list[str]:
    """Names of the presets of one kind ('airframes' or 'scenarios')."""
    return sorted(p.name[:-5] for p in _preset_dir(kind).iterdir() if p.name.endswith(".toml"))


def _read_toml(source, label: str) -> dict:
    try:
        text = source.read_text(encoding="utf-8")
    except FileNotFoundError as exc:
        raise ConfigError(f"{label}: file not found") from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{label}: not valid TOML ({exc})") from exc


def _preset(kind: str, name: str) -> dict:
    return copy.deepcopy(_parsed_preset(kind, name))


@functools.lru_cache(maxsize=64)
def _parsed_preset(kind: str, name: str) -> dict:
    """A preset file parsed once per process (presets are package data); callers copy it."""
    path = _preset_dir(kind) / f"{name}.toml"
    if not path.is_file():
        raise ConfigError(f"unknown {kind[:-1]} preset {name!r}: choose one of {', '.join(available(kind))}")
    return _read_toml(path, f"{kind[:-1]} preset {name!r}")


@functools.lru_cache(maxsize=None)
def _base_preset() -> dict:
    return _read_toml(_preset_dir() / "rig.toml", "base preset rig.toml")


def _airframe_layers(airframe: str, seen: tuple = ()) -> tuple[dict, list[str]]:
    """An airframe preset's ``airframe.*`` table and the hardware presets it selects.

    Two keys of an airframe file are not parameters: ``based_on = "NAME"`` takes another
    airframe preset's values first (``hilms`` is ``hilms-ideal`` plus its hardware) and
    ``hardware = "NAME"`` layers ``presets/hardware/NAME.toml`` (any parameter tables: the
    real rig's effects and readings) over ``rig.toml``.
    """
    if airframe in seen:
        raise ConfigError(f"airframe preset {airframe!r}: based_on forms a loop ({' -> '.join(seen + (airframe,))})")
    own = _preset("airframes", airframe)
    base = own.pop("based_on", None)
    hardware = own.pop("hardware", None)
    table, hw = ({}, []) if base is None else _airframe_layers(str(base), seen + (airframe,))
    table.update(own)
    if hardware is not None:
        hw.append(str(hardware))
    return table, hw


def _preset_layers(airframe: str, scenario: str | None) -> dict[str, Any]:
    flat = flatten(copy.deepcopy(_base_preset()))
    table, hardware = _airframe_layers(airframe)
    for name in hardware:
        flat.update(flatten(_preset("hardware", name)))
    flat.update(flatten({"airframe": table}))
    flat["airframe.name"] = airframe
    if scenario is not None:
        flat.update(flatten(_preset("scenarios", scenario)))
    return flat


@functools.lru_cache(maxsize=64)
def _validated_presets(airframe: str, scenario: str | None) -> "RigConfig":
    """The validated preset layers of (airframe, scenario), once per process; never handed out
    itself (its lists and tables are copied for every caller)."""
    return validate(_preset_layers(airframe, scenario))


def flatten(tree: Mapping, prefix: str = "") -> dict[str, Any]:
    """Nested tables -> dotted keys. Lists of tables stay whole (they are one parameter)."""
    out: dict[str, Any] = {}
    for key, value in tree.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, Mapping) and dotted not in SCHEMA:
            out.update(flatten(value, dotted + "."))
        else:
            out[dotted] = value
    return out


def _check_number(key: str, spec: Spec, value: Any, integer: bool) -> float | int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{key} = {value!r}: must be a number {spec.describe_range()}")
    if integer and (isinstance(value, float) and not value.is_integer()):
        raise ConfigError(f"{key} = {value!r}: must be an integer {spec.describe_range()}")
    if not math.isfinite(value):
        raise ConfigError(f"{key} = {value!r}: must be finite, {spec.describe_range()}")
    below = value <= spec.lo if spec.lo_open else value < spec.lo
    if below or value > spec.hi:
        unit = f" {spec.unit}" if spec.unit else ""
        raise ConfigError(f"{key} = {value!r}: must be {spec.describe_range()}{unit}")
    if spec.in_gap(value):
        unit = f" {spec.unit}" if spec.unit else ""
        raise ConfigError(f"{key} = {value!r}: must be {spec.describe_gap()}{unit}")
    return int(value) if integer else float(value)


def check_value(key: str, spec: Spec, value: Any) -> Any:
    """Validate one value against its spec and return it normalised."""
    if spec.kind == "float":
        return _check_number(key, spec, value, integer=False)
    if spec.kind == "int":
        return _check_number(key, spec, value, integer=True)
    if spec.kind == "bool":
        if not isinstance(value, bool):
            raise ConfigError(f"{key} = {value!r}: must be true or false")
        return value
    if spec.kind == "str":
        if not isinstance(value, str):
            raise ConfigError(f"{key} = {value!r}: must be a string")
        if spec.choices and value not in spec.choices:
            raise ConfigError(f"{key} = {value!r}: must be {spec.describe_range()}")
        return value
    if spec.kind in ("vec3", "floats"):
        if key == "guidance.waypoints":
            return _check_waypoints(key, value)
        if not isinstance(value, list):
            raise ConfigError(f"{key} = {value!r}: must be a list of numbers")
        if spec.length is not None and len(value) != spec.length:
            raise ConfigError(f"{key} = {value!r}: must have exactly {spec.length} numbers")
        return [_check_number(f"{key}[{i}]", spec, v, integer=False) for i, v in enumerate(value)]
    if spec.kind == "tree":
        if not isinstance(value, Mapping):
            raise ConfigError(f"{key}: must be a table of overrides ([{key}] in TOML)")
        from rig_emulator.sensors.presets import load_sensor_preset  # the sensor presets validate their own trees

        try:
            load_sensor_preset(key.split(".", 1)[1], value)
        except ValueError as exc:
            raise ConfigError(f"{key}: {exc}") from None
        return dict(value)
    if spec.kind == "params":
        if not isinstance(value, Mapping):
            raise ConfigError(f"{key}: must be a table of name = number or list of numbers ([{key}] in TOML)")
        out = {}
        for name, v in value.items():
            if isinstance(v, list):
                out[name] = [_check_number(f"{key}.{name}[{i}]", spec, x, integer=False) for i, x in enumerate(v)]
            else:
                out[name] = _check_number(f"{key}.{name}", spec, v, integer=False)
        return out
    if spec.kind == "table_list":
        if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
            raise ConfigError(f"{key}: must be a list of tables ([[{key}]] in TOML)")
        items = []
        for i, entry in enumerate(value):
            unknown = set(entry) - set(spec.item)
            if unknown:
                raise ConfigError(f"{key}[{i}]: unknown field(s) {sorted(unknown)}; allowed: {sorted(spec.item)}")
            missing = set(spec.item) - set(entry)
            if missing:
                raise ConfigError(f"{key}[{i}]: missing field(s) {sorted(missing)}")
            items.append({f: check_value(f"{key}[{i}].{f}", s, entry[f]) for f, s in spec.item.items()})
        return items
    raise ConfigError(f"{key}: schema kind {spec.kind!r} is not known to the loader")


def _check_waypoints(key: str, value: Any) -> list[list[float]]:
    if not isinstance(value, list) or not all(isinstance(w, list) and len(w) == 3 for w in value):
        raise ConfigError(f"{key}: must be a list of [x, y, z] triples in metres")
    spec = Spec("float", "waypoint coordinate", "m", -1e5, 1e5)
    return [[_check_number(f"{key}[{i}][{j}]", spec, c, integer=False) for j, c in enumerate(w)] for i, w in enumerate(value)]


class RigConfig(dict):
    """Validated parameters as ``{dotted_key: value}`` (SI apart from keys named with their unit)."""

    def with_overrides(self, overrides: Mapping[str, Any]) -> "RigConfig":
        merged = dict(self)
        merged.update(overrides)
        return validate(merged)

    def section(self, prefix: str) -> dict[str, Any]:
        return {k[len(prefix) + 1 :]: v for k, v in self.items() if k.startswith(prefix + ".")}


def _divisor(key: str, rate: float, physics_rate: float) -> None:
    ratio = physics_rate / rate
    if abs(ratio - round(ratio)) > 1e-9:
        raise ConfigError(
            f"{key} = {rate:g}: must divide sim.physics_rate_hz = {physics_rate:g} into a whole number of steps"
        )


def _unknown(key: str) -> ConfigError:
    hint = difflib.get_close_matches(key, SCHEMA.keys(), n=1)
    suffix = f" (did you mean {hint[0]!r}?)" if hint else ""
    return ConfigError(f"unknown parameter {key!r}{suffix}")


PLUGIN_PARAMS = "controller.params"


def fold_plugin_params(flat: Mapping[str, Any], current: Mapping[str, Any] | None = None) -> Mapping[str, Any]:
    """``controller.params.NAME = value`` keys (``--set controller.params.kp=1``) folded into the
    one parameter ``controller.params`` (a table, over ``flat``'s own table or else ``current``'s);
    ``flat`` itself when it has none. The plug-in's own rules (its names, the ``param_info``
    ranges) are checked where the plug-in is loaded (:func:`rig_emulator.controllers.load_controller`)."""
    dotted = [k for k in flat if isinstance(k, str) and k.startswith(PLUGIN_PARAMS + ".")]
    if not dotted:
        return flat
    out = {k: v for k, v in flat.items() if k not in dotted}
    table = out.get(PLUGIN_PARAMS, (current or {}).get(PLUGIN_PARAMS, {}))
    if not isinstance(table, Mapping):
        raise ConfigError(f"{PLUGIN_PARAMS}: must be a table of overrides ([{PLUGIN_PARAMS}] in TOML)")
    table = dict(table)
    for key in dotted:
        name = key[len(PLUGIN_PARAMS) + 1:]
        if not name.isidentifier():
            raise ConfigError(f"unknown parameter {key!r}: a plug-in parameter is {PLUGIN_PARAMS}.NAME, NAME a "
                              "Python identifier (a list parameter is set whole, e.g. controller.params.k=[1,2,3])")
        table[name] = flat[key]
    out[PLUGIN_PARAMS] = table
    return out


def validate(flat: Mapping[str, Any]) -> RigConfig:
    """Check every key of a flat config; raise :class:`ConfigError` naming the first bad one."""
    flat = fold_plugin_params(flat)
    unknown = [k for k in flat if k not in SCHEMA]
    if unknown:
        raise _unknown(unknown[0])
    missing = [k for k in SCHEMA if k not in flat]
    if missing:
        raise ConfigError(f"missing parameter {missing[0]!r}: {SCHEMA[missing[0]].doc}")
    out = RigConfig({k: check_value(k, SCHEMA[k], flat[k]) for k in SCHEMA})
    _cross_checks(out)
    return out


def _validate_over(base: RigConfig, overrides: Mapping[str, Any], copy_base: bool = True) -> RigConfig:
    """``validate({**base, **overrides})`` for a ``base`` already validated: the overrides are
    checked key by key, in schema order as :func:`validate` does, then the cross-key checks.
    ``copy_base=False`` shares the base's values with the result (for a check whose result is
    thrown away)."""
    overrides = fold_plugin_params(overrides, base)
    for k in overrides:
        if k not in SCHEMA:
            raise _unknown(k)
    out = RigConfig(fast_deepcopy(dict(base)) if copy_base else base)
    for k in SCHEMA:
        if k in overrides:
            out[k] = check_value(k, SCHEMA[k], overrides[k])
    _cross_checks(out)
    return out


def _cross_checks(out: RigConfig) -> None:
    physics = out["sim.physics_rate_hz"]
    for key in ("sim.control_rate_hz", "sim.log_rate_hz"):
        if out[key] > physics:
            raise ConfigError(f"{key} = {out[key]:g}: must not exceed sim.physics_rate_hz = {physics:g}")
        _divisor(key, out[key], physics)
    if out["guidance.type"] == "waypoints" and not out["guidance.waypoints"]:
        raise ConfigError("guidance.waypoints: guidance.type = 'waypoints' needs at least one waypoint")


def load_config(
    airframe: str = "hilms",
    scenario: str | None = None,
    files: Iterable[str | Path] = (),
    overrides: Mapping[str, Any] | None = None,
) -> RigConfig:
    """Merge the layers described in the module docstring and validate the result.

    Without ``files`` the presets' validated merge is reused (computed once per process for
    each airframe and scenario) and only the overrides are checked on top of it, with the
    cross-key checks of :func:`validate` run again: the same result and the same errors as
    validating the whole merge, for many runs of one scenario at a fraction of the cost.
    """
    files = list(files)
    if not files:
        base = _validated_presets(airframe, scenario)
        if not overrides:
            return RigConfig(fast_deepcopy(dict(base)))
        return _validate_over(base, overrides)
    flat = _preset_layers(airframe, scenario)
    for path in files:
        layer = flatten(_read_toml(Path(path), str(path)))
        cal = layer.get("sensors.calibration_file")
        if isinstance(cal, str) and cal and not Path(cal).is_absolute():
            # a calibration file named in a config file sits next to that config file
            layer["sensors.calibration_file"] = str(Path(path).resolve().parent / cal)
        flat.update(layer)
    if overrides:
        flat.update(overrides)
    return validate(flat)


def check_config(airframe: str = "hilms", scenario: str | None = None,
                 overrides: Mapping[str, Any] | None = None) -> None:
    """Raise the :class:`ConfigError` that :func:`load_config` would raise for these presets
    and overrides, without building the configuration (checking a thousand sweep jobs up
    front costs a millisecond or two, not the copies)."""
    base = _validated_presets(airframe, scenario)
    if overrides:
        _validate_over(base, overrides, copy_base=False)


def parse_override(text: str) -> tuple[str, Any]:
    """``key=value`` with a TOML value (``smc.switching="boundary"``, ``smc.k=[2,2,2]``).

    A bare word that is not valid TOML is taken as a string, so ``control.strategy=flc`` works.
    """
    if "=" not in text:
        raise ConfigError(f"override {text!r}: expected KEY=VALUE")
    key, raw = (part.strip() for part in text.split("=", 1))
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key, value
