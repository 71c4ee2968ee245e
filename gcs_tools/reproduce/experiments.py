"""The experiments of the reproduction, in report order (``rig-gcs reproduce --only NAME``).

Each is a module ``exp_<NAME>`` with ``NAME``, ``TITLE``, ``PAPER``, ``jobs(ctx)``, optionally
``live(ctx)`` and ``analyse(ctx, results, live)`` (see :mod:`gcs_tools.reproduce.experiment`).
The names are known without importing the modules (``rig-gcs --help`` lists them and starts
fast); ``EXPERIMENTS`` and ``BY_NAME`` import them on first use (PEP 562).
"""

from __future__ import annotations

from importlib import import_module

ORDER = ("shocks", "harmonic", "sweep", "masses", "helix", "altitude", "rectangle")  # report order
STABILITY = "stability"  # the FLC stability analysis section (gcs_tools.stability), not a simulation
NAMES = ORDER + (STABILITY,)


def _load() -> tuple:
    modules = tuple(import_module(f"gcs_tools.reproduce.exp_{name}") for name in ORDER)
    for name, module in zip(ORDER, modules):
        if module.NAME != name:
            raise RuntimeError(f"{module.__name__}: NAME is {module.NAME!r}, expected {name!r}")
    return modules


def __getattr__(name: str):
    if name == "EXPERIMENTS":
        value = _load()
    elif name == "BY_NAME":
        value = {e.NAME: e for e in _load()}
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value
