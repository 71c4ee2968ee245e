"""The report's section on the FLC stability analysis (Eq. 16-32), from :mod:`gcs_tools.stability`.

This is the single call site: the analysis is another module's work (``rig-gcs stability``);
the report includes its markdown as it is. When the module or its optional solver (the
``analysis`` extra: cvxpy, clarabel) is missing, the section says so instead.
"""

from __future__ import annotations


def stability_section() -> tuple[str, dict | None]:
    """(markdown section, JSON-able dict or None when the analysis is unavailable)."""
    try:
        from gcs_tools.stability import analyse
    except ImportError as exc:
        return _missing(f"the module gcs_tools.stability could not be imported ({exc})"), None
    try:
        result = analyse(config=None)
    except ImportError as exc:
        return _missing(f"its solver is not installed ({exc}); pip install 'hilms-sil[analysis]'"), None
    except Exception as exc:  # noqa: BLE001 - AnalysisUnavailable and solver failures: reported, not hidden
        return _missing(f"{type(exc).__name__}: {exc}"), None
    return result.to_markdown().rstrip() + "\n", result.to_dict()


def _missing(reason: str) -> str:
    return ("## FLC stability (Eq. 16-32)\n\nNot included in this report: " + reason + ".\n")
