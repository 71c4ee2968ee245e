"""Settings of the FLC stability analysis (Eq. 16-32): data in ``settings.toml``, ranges here.

These choose *how* the analysis is done (fit rectangle of Eq. 16, margin and solver of the
LMI of Eq. 32, the rate bound behind ``g_max`` of Eq. 27); the rig's own parameters stay in
:mod:`rig_emulator.config.schema`. Values are validated with the rig loader's
:func:`~rig_emulator.config.loader.check_value`, so a bad value is rejected with its key and
allowed range. Non-SI values carry their unit in the key (``desired_rate_max_deg_s``).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from importlib import resources
from typing import Any, Mapping

from rig_emulator.config.loader import ConfigError, check_value, flatten
from rig_emulator.config.schema import F, I, S, V3

#: Prefix under which the settings are addressed from the command line (``--set stability.fit.scale=0.5``).
PREFIX = "stability."

SOLVERS = ("CLARABEL", "SCS")

SETTINGS_SCHEMA = {
    "fit.scale": F("fit rectangle of Eq. 16 as a fraction of each input's saturation edge", "", 0.0, 2.0, lo_open=True),
    "fit.grid_points": I("grid points per side of the fit rectangle", 5, 1001),
    "lmi.margin": F("Eq. 32 with margin: F^T P + P F <= -margin I", "", 0.0, 1e6, lo_open=True),
    "lmi.p_floor": F("Eq. 32 with margin: P >= p_floor I", "", 0.0, 1e3, lo_open=True),
    "lmi.condition_cap": F("cond(P) bound of the infeasibility measure t* (I <= P <= cap I)", "", 1.0, 1e8, lo_open=True),
    "lmi.solver": S("cvxpy solver for the LMI", SOLVERS),
    "bound.desired_rate_max_deg_s": V3(
        "bound on |desired Euler rates| (phi, theta, psi) behind g_max of Eq. 27", "deg/s", 0.0, 1e4
    ),
}


@dataclass(frozen=True)
class Settings:
    """Validated analysis settings (SI apart from the key named with its unit)."""

    fit_scale: float
    fit_grid_points: int
    lmi_margin: float
    lmi_p_floor: float
    lmi_solver: str
    lmi_condition_cap: float
    desired_rate_max_deg_s: tuple[float, float, float]

    @property
    def desired_rate_max(self) -> tuple[float, float, float]:
        """:attr:`desired_rate_max_deg_s` in rad/s."""
        return tuple(math.radians(v) for v in self.desired_rate_max_deg_s)

    def to_dict(self) -> dict[str, Any]:
        return {
            "fit.scale": self.fit_scale,
            "fit.grid_points": self.fit_grid_points,
            "lmi.margin": self.lmi_margin,
            "lmi.p_floor": self.lmi_p_floor,
            "lmi.solver": self.lmi_solver,
            "lmi.condition_cap": self.lmi_condition_cap,
            "bound.desired_rate_max_deg_s": list(self.desired_rate_max_deg_s),
        }


def _defaults() -> dict[str, Any]:
    text = (resources.files("gcs_tools.stability") / "settings.toml").read_text(encoding="utf-8")
    return flatten(tomllib.loads(text))


def load_settings(overrides: Mapping[str, Any] | None = None) -> Settings:
    """The defaults of ``settings.toml`` with ``overrides`` (dotted keys, with or without the
    ``stability.`` prefix) applied and every value checked; :class:`ConfigError` names a bad key."""
    flat = _defaults()
    for key, value in (overrides or {}).items():
        bare = key[len(PREFIX):] if key.startswith(PREFIX) else key
        if bare not in SETTINGS_SCHEMA:
            raise ConfigError(
                f"unknown analysis setting '{PREFIX}{bare}'; known: {', '.join(PREFIX + k for k in SETTINGS_SCHEMA)}"
            )
        flat[bare] = value
    missing = [k for k in SETTINGS_SCHEMA if k not in flat]
    unknown = [k for k in flat if k not in SETTINGS_SCHEMA]
    if missing or unknown:  # settings.toml and the schema disagree: a packaging error
        raise ConfigError(f"settings.toml does not match the schema (missing {missing}, unknown {unknown})")
    v = {k: check_value(PREFIX + k, spec, flat[k]) for k, spec in SETTINGS_SCHEMA.items()}
    return Settings(
        fit_scale=v["fit.scale"],
        fit_grid_points=v["fit.grid_points"],
        lmi_margin=v["lmi.margin"],
        lmi_p_floor=v["lmi.p_floor"],
        lmi_solver=v["lmi.solver"],
        lmi_condition_cap=v["lmi.condition_cap"],
        desired_rate_max_deg_s=tuple(v["bound.desired_rate_max_deg_s"]),
    )
