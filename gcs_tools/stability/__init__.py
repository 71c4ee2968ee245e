"""Stability analysis of the FLC attitude controller (Eq. 16-32 of the paper).

``analyse(config=None) -> StabilityResult``; ``result.to_markdown()`` is a report section,
``result.to_dict()`` its JSON form. Needs the optional extra ``analysis`` (cvxpy, clarabel);
without it :class:`AnalysisUnavailable` says how to install it. See docs/STABILITY.md.
"""

from gcs_tools.stability.analysis import analyse, analyse_gains
from gcs_tools.stability.lmi import INSTALL_HINT, AnalysisUnavailable
from gcs_tools.stability.result import StabilityResult
from gcs_tools.stability.settings import Settings, load_settings

__all__ = [
    "analyse", "analyse_gains", "StabilityResult", "AnalysisUnavailable", "INSTALL_HINT", "Settings", "load_settings",
]
