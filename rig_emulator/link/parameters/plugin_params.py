"""A controller plug-in's own parameters as MAVLink parameters (docs/how-to/your-controller.md).

A plug-in declares ``params`` (name -> number or list of numbers) and ``param_prefix``
(upper case, ends with ``_``; empty: none served). Each scalar is the parameter
``<prefix><NAME>``, each element of a list ``<prefix><NAME><i>`` numbered from 1 (as the
rig's own ``FLC_R1``..``FLC_R4``); e.g. ``HOV_`` + ``kp_z`` -> ``HOV_KP_Z``. They follow the
rig's parameters in the table (indexes after the last rig parameter), REAL32 like them.

A PARAM_SET changes the config key ``controller.params`` through
:meth:`LiveRig.set_params`, which validates it with the plug-in's own rules (finite, the
``param_info`` range) and writes the running controller's ``params.array`` in place: the
controller sees the value at its next call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rig_emulator.controllers.base import PluginError

NAME_MAX = 16  # MAVLink param_id


@dataclass(frozen=True)
class PluginSpec:
    """What the table and the metadata need of a plug-in parameter (as a schema ``Spec``)."""

    kind: str
    unit: str
    doc: str
    lo: float
    hi: float
    lo_open: bool = False
    choices: tuple = ()


class Fixed:
    """A source whose controller never changes (a table built for one controller object)."""

    def __init__(self, controller):
        self.controller = controller


@dataclass(frozen=True)
class PluginParam:
    """One served element of a plug-in parameter: ``param`` (``element`` of a list) of the
    controller ``source.controller`` flies with now (a :class:`LiveRig` as the source: a
    REBOOT builds a new controller object from the configuration, the table stays)."""

    index: int
    name: str
    param: str
    element: int | None
    spec: PluginSpec
    source: object
    key: str = "controller.params"

    @property
    def controller(self):
        return self.source.controller

    def _slot(self) -> int:
        sl = self.controller.params.index(self.param)
        return sl.start + (self.element or 0)

    def value(self, cfg=None) -> float:
        """The running controller's value (what it sees at its next call)."""
        return float(self.controller.params.array[self._slot()])

    def default(self) -> float:
        d = type(self.controller).params[self.param]
        return float(d[self.element]) if self.element is not None else float(d)

    def to_config(self, value: float, cfg) -> dict:
        """The new ``controller.params`` (every current value, this one changed); ValueError when unusable."""
        if not math.isfinite(value):
            raise ValueError(f"{self.name}: {value} is not a finite number")
        if not self.spec.lo <= value <= self.spec.hi:
            raise ValueError(f"{self.name}: {value:g} is outside [{self.spec.lo:g}, {self.spec.hi:g}]")
        current = self.controller.params.as_dict()
        if self.element is None:
            current[self.param] = value
        else:
            current[self.param][self.element] = value
        return current

    @property
    def unit(self) -> str:
        return self.spec.unit


def plugin_params(controller, first_index: int, taken: set[str], source=None) -> list[PluginParam]:
    """The served parameters of ``controller`` (None: none), indexes from ``first_index``;
    ``source.controller`` is the controller they act on (default: ``controller`` itself).

    Raises :class:`PluginError` when the prefix is malformed, a name is longer than 16
    characters or collides with another parameter."""
    if controller is None:
        return []
    prefix = type(controller).param_prefix or ""
    name = getattr(controller, "plugin_name", type(controller).__qualname__)
    if not prefix:
        return []
    if not (prefix.endswith("_") and prefix.upper() == prefix and prefix[:-1].replace("_", "").isalnum()
            and prefix[0].isalpha()):
        raise PluginError(name, f"param_prefix = {prefix!r}: must be upper-case letters, digits and '_', "
                                f"start with a letter and end with '_' (e.g. 'MYC_')")
    cp = controller.params
    source = source if source is not None else Fixed(controller)
    out: list[PluginParam] = []
    for pname in cp.names():
        sl = cp.index(pname)
        info = cp.info.get(pname, {})
        lo, hi = cp.limits(pname)
        owner = f"parameter {pname!r} of controller {name}"
        spec = PluginSpec("float", str(info.get("unit", "")), str(info.get("doc", owner)), lo, hi)
        scalar = cp._scalar[pname]
        elements = [None] if scalar else list(range(sl.stop - sl.start))
        for e in elements:
            full = prefix + pname.upper() + ("" if e is None else str(e + 1))
            if len(full) > NAME_MAX:
                raise PluginError(name, f"parameter {pname!r} would be served as {full!r}, longer than "
                                        f"{NAME_MAX} characters; shorten its name or param_prefix")
            if full in taken:
                raise PluginError(name, f"parameter {pname!r} would be served as {full!r}, which is taken")
            taken.add(full)
            out.append(PluginParam(first_index + len(out), full, pname, e, spec, source))
    return out
