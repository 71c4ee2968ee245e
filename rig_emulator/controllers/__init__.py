"""Your controller on the rig: in-process controller plug-ins (docs/how-to/your-controller.md).

>>> from rig_emulator.controllers import Controller
>>> class Hover(Controller):
...     replaces, commands = "both", "torques"
...     def update(self, t, obs):
...         return (obs.mass * obs.gravity, 0.0, 0.0, 0.0)

Run it: ``rig-emulator simulate --scenario hover --controller my_module:Hover``, or
``rig_emulator.api.simulate("hover", controller=Hover())``.

The package holds the interface (this module, :mod:`.base`, :mod:`.observation`, :mod:`.runtime`),
the built-in strategies (:mod:`.builtin`: one compiled kernel on this interface, which the loop calls
as it calls a plug-in) and the examples (:mod:`.examples`).

The base classes import without numba; the loader and the observation views (which need the
compiled side) are imported on first use.
"""

from rig_emulator.control import plugin_layout as layout
from rig_emulator.controllers.base import (
    ALLOWED,
    COMMANDS,
    REPLACES,
    Command,
    CompiledController,
    Controller,
    ControllerParams,
    PluginError,
)

_LAZY = {
    "Observation": "rig_emulator.controllers.observation",
    "Reference": "rig_emulator.controllers.observation",
    "BoundPlugin": "rig_emulator.controllers.runtime",
    "bind": "rig_emulator.controllers.runtime",
    "load_controller": "rig_emulator.controllers.runtime",
    "no_plugin_binding": "rig_emulator.controllers.runtime",
    "plugin_name": "rig_emulator.controllers.runtime",
}

__all__ = ["ALLOWED", "COMMANDS", "REPLACES", "Command", "CompiledController", "Controller", "ControllerParams",
           "PluginError", "layout", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'rig_emulator.controllers' has no attribute {name!r}")
