"""Parameters set over MAVLink, stored in the state directory (``params.json``).

The document holds every parameter a PARAM_SET changed (by its MAVLink name, with the
REAL32 value the ground station sent), not the whole table::

    {"format": "hilms-sil parameters", "version": 1, "params": {"SMC_K_PHI": 2.5, "WP_RADIUS": 0.1},
     "plugins": {"my_pkg.mod:MyController": {"MYC_KP": 3.0}}}

A controller plug-in's parameters are kept under ``plugins`` by the plug-in's name (optional
key): they are applied when that plug-in flies the rig again, and a rig started with
another plug-in (or none) leaves them stored but unused.

It is rewritten (atomically, see :mod:`rig_emulator.link.state.directory`) on each accepted PARAM_SET *before* the
rig answers with PARAM_VALUE, so an acknowledged value is on disk; when it cannot be
written the change is undone and refused. On start the stored values are applied over the
configuration (presets, ``--config``, ``--set``), as ArduPilot applies its stored
parameters over its defaults; ``--wipe`` starts from the configuration again.
"""

from __future__ import annotations

import math

from rig_emulator.config.loader import ConfigError
from rig_emulator.controllers.base import PluginError
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.link.state.directory import StateDir

FILE = "params.json"
FORMAT = "hilms-sil parameters"
VERSION = 1
RENAMED = {"GUI_SPEED": "MPC_XY_CRUISE"}  # names a stored document may still use -> the name served now


def parse_params(doc: dict, state: StateDir, table: ParamTable) -> dict[str, float]:
    """name -> value of a params document (names known, values finite numbers)."""
    params = doc.get("params")
    if not isinstance(params, dict):
        raise state.error(FILE, "params", "expected an object of NAME: value")
    out = {}
    for name, value in params.items():
        if name in RENAMED and RENAMED[name] not in params:
            name = RENAMED[name]  # served under PX4's name; rewritten so on the next save
        if name not in table.by_name:
            raise state.error(FILE, f"params.{name}", "no such parameter on this rig")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise state.error(FILE, f"params.{name}", f"expected a finite number, got {value!r}"[:120])
        out[name] = float(value)
    return out


def parse_plugins(doc: dict, state: StateDir) -> dict[str, dict[str, float]]:
    """plug-in name -> (parameter name -> value) of a params document (optional ``plugins``)."""
    plugins = doc.get("plugins", {})
    if not isinstance(plugins, dict):
        raise state.error(FILE, "plugins", "expected an object of PLUGIN: {NAME: value}")
    out = {}
    for plugin, params in plugins.items():
        if not isinstance(params, dict):
            raise state.error(FILE, f"plugins.{plugin}", "expected an object of NAME: value")
        for name, value in params.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise state.error(FILE, f"plugins.{plugin}.{name}", f"expected a finite number, got {value!r}"[:120])
        out[plugin] = {name: float(v) for name, v in params.items()}
    return out


class ParamStore:
    def __init__(self, state: StateDir, table: ParamTable | None = None):
        self.state = state
        self.table = table or ParamTable()
        doc = state.read_json(FILE, FORMAT, VERSION)
        self.values: dict[str, float] = {} if doc is None else parse_params(doc, state, self.table)
        self.plugins: dict[str, dict[str, float]] = {} if doc is None else parse_plugins(doc, state)

    def apply(self, rig) -> list[str]:
        """Set the stored values on ``rig`` (in table order); returns the names applied.

        A value the rig refuses (out of its range, a restart-only parameter) is a StateError
        naming the file and the parameter."""
        applied = []
        for p in self.table.params:
            if p.name not in self.values:
                continue
            try:
                rig.set_param(p.key, p.to_config(self.values[p.name], rig.cfg))
            except (ConfigError, ValueError) as exc:
                raise self.state.error(FILE, f"params.{p.name}", str(exc)) from None
            applied.append(p.name)
        controller = getattr(rig, "controller", None)
        stored = self.plugins.get(getattr(controller, "plugin_name", None), {}) if controller is not None else {}
        if stored:
            table = ParamTable(controller)
            for name, value in stored.items():
                p = table.by_name.get(name)
                if p is None or not hasattr(p, "controller"):
                    raise self.state.error(FILE, f"plugins.{controller.plugin_name}.{name}",
                                           "the plug-in has no such parameter (any more)")
                try:
                    rig.set_param(p.key, p.to_config(value, rig.cfg))
                except (ConfigError, ValueError, PluginError) as exc:
                    raise self.state.error(FILE, f"plugins.{controller.plugin_name}.{name}", str(exc)) from None
                applied.append(name)
        return applied

    def save(self, name: str, value: float, plugin: str | None = None) -> None:
        """Store ``name = value`` (a parameter of controller plug-in ``plugin`` when given) with
        everything stored before; StateWriteError leaves both as they were."""
        values = self.values if plugin is None else self.plugins.setdefault(plugin, {})
        previous = values.get(name)
        values[name] = float(value)
        doc = {"format": FORMAT, "version": VERSION, "params": dict(self.values)}
        if any(self.plugins.values()):
            doc["plugins"] = {k: dict(v) for k, v in self.plugins.items() if v}
        try:
            self.state.write_json(FILE, doc)
        except Exception:
            if previous is None:
                del values[name]
            else:
                values[name] = previous
            raise
