"""Stability analysis of the FLC attitude controller (Eq. 16-32 of the paper).

``analyse(config=None) -> StabilityResult``; ``result.to_markdown()`` is a report section,
``result.to_dict()`` its JSON form. Needs the optional extra ``analysis`` (cvxpy, clarabel);
without it :class:`AnalysisUnavailable` says how to install it. See docs/explanation/stability.md.

The names below are imported on first use (PEP 562): ``rig-gcs --help`` and the other
commands import ``gcs_tools.stability.command`` for its arguments without loading numba,
scipy and the fuzzy controller.
"""

from importlib import import_module

_WHERE = {
    "analyse": "analysis", "analyse_gains": "analysis", "INSTALL_HINT": "lmi", "AnalysisUnavailable": "lmi",
    "StabilityResult": "result", "Settings": "settings", "load_settings": "settings",
}

__all__ = [
    "analyse", "analyse_gains", "StabilityResult", "AnalysisUnavailable", "INSTALL_HINT", "Settings", "load_settings",
]


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(import_module(f"{__name__}.{_WHERE[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
