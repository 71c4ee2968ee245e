"""Column names that carry their unit, for every CSV the project writes.

The project's convention (DEVELOPERS.md: ``thrust_grf``, ``angle_deg``; the mean errors
``phi_deg``, ``x_m``; the load-cell values ``LC1_N``) puts the unit at the end of a name
after an underscore. :func:`with_unit` does that for CSV headers: ``with_unit("pos_0", "m")``
is ``pos_0_m``, ``with_unit("ATTITUDE.roll", "rad")`` is ``ATTITUDE.roll_rad``. A unit is
written as a token a CSV reader keeps in a column name (``numpy.genfromtxt(names=True)``
drops ``/``): ``m/s`` becomes ``m_s``, ``N m`` becomes ``Nm``, ``%`` becomes ``pct``. A name
that already ends with its unit (``time_boot_ms``, ``thrust_n``, ``force_grf``) is kept as it
is; a dimensionless value (no unit) too.
"""

from __future__ import annotations

import re

_SAME = {"gf": ("grf", "gf")}  # gram-force: the project writes grf, MAVLink's XML gf


def unit_token(unit: str) -> str:
    """``unit`` as a name-safe token: ``m/s`` -> ``m_s``, ``N m`` -> ``Nm``, ``m/s*5`` -> ``m_sx5``."""
    text = unit.strip().replace("%", "pct").replace("*", "x").replace("/", "_").replace("^", "")
    return re.sub(r"[^0-9A-Za-z_]", "", text.replace(" ", ""))


def with_unit(name: str, unit: str | None) -> str:
    """``name`` followed by ``_`` and its unit token, unless it has no unit or ends with it already."""
    token = unit_token(unit or "")
    if not token:
        return name
    base = name.split("[", 1)[0].lower()  # HILMS_LOAD_CELLS.thrust_n[2]: the field name decides
    if any(base.endswith("_" + t.lower()) for t in _SAME.get(token, (token,))):
        return name
    return f"{name}_{token}"
