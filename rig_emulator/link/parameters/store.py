"""Parameters set over MAVLink, stored in the state directory (``params.json``).

The document holds every parameter a PARAM_SET changed (by its MAVLink name, with the
REAL32 value the ground station sent), not the whole table::

    {"format": "hilms-sil parameters", "version": 1, "params": {"SMC_K_PHI": 2.5, "WP_RADIUS": 0.1}}

It is rewritten (atomically, see :mod:`rig_emulator.link.state.directory`) on each accepted PARAM_SET *before* the
rig answers with PARAM_VALUE, so an acknowledged value is on disk; when it cannot be
written the change is undone and refused. On start the stored values are applied over the
configuration (presets, ``--config``, ``--set``), as ArduPilot applies its stored
parameters over its defaults; ``--wipe`` starts from the configuration again.
"""

from __future__ import annotations

import math

from rig_emulator.config.loader import ConfigError
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
            name = RENAMED[name]  # served under PX4's name since issue 15; rewritten so on the next save
        if name not in table.by_name:
            raise state.error(FILE, f"params.{name}", "no such parameter on this rig")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise state.error(FILE, f"params.{name}", f"expected a finite number, got {value!r}"[:120])
        out[name] = float(value)
    return out


class ParamStore:
    def __init__(self, state: StateDir, table: ParamTable | None = None):
        self.state = state
        self.table = table or ParamTable()
        doc = state.read_json(FILE, FORMAT, VERSION)
        self.values: dict[str, float] = {} if doc is None else parse_params(doc, state, self.table)

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
        return applied

    def save(self, name: str, value: float) -> None:
        """Store ``name = value`` with everything stored before; StateWriteError leaves both as they were."""
        previous = self.values.get(name)
        self.values[name] = float(value)
        try:
            self.state.write_json(FILE, {"format": FORMAT, "version": VERSION, "params": dict(self.values)})
        except Exception:
            if previous is None:
                del self.values[name]
            else:
                self.values[name] = previous
            raise
