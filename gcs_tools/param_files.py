"""Parameter files: QGroundControl's ``.params`` and MAVProxy's ``NAME VALUE`` lists.

* **QGroundControl** (what ``rig-gcs param save`` writes, what QGroundControl's "Save to file"
  writes): ``#`` comment lines, then one parameter a line, five tab-separated fields
  ``sysid compid name value type`` (``type`` a MAV_PARAM_TYPE: 1..8 integers, 9 REAL32,
  10 REAL64).
* **MAVProxy** (``param save``): ``NAME VALUE`` a line (whitespace or ``=`` between them),
  ``#`` comments.

:func:`parse_params` reads either (the first parameter line decides; every line must then
have that form) and checks every line before returning: a name of 1..16 characters
``[A-Za-z0-9_]``, each name once, a finite number that fits the line's type (REAL32 within
+-3.4e38; integer types whole and in range), ids in 0..255 and a known type. Any problem
raises :class:`ParamFileError` naming the file, the line and the field; nothing is returned
half-read. :func:`write_params` writes the QGroundControl form, REAL32 values as the
shortest decimal of their float32 value (so save -> load sets exactly what was read).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from gcs_tools.errors import UsageError
from protocol.atomic_file import atomic_write_text
from protocol.dialect import mavlink as M
from protocol.text_file import read_text

NAME_RE = re.compile(r"^[A-Za-z0-9_]{1,16}$")
REAL32, REAL64 = M.MAV_PARAM_TYPE_REAL32, M.MAV_PARAM_TYPE_REAL64
INT_RANGES = {
    M.MAV_PARAM_TYPE_UINT8: (0, 2**8 - 1), M.MAV_PARAM_TYPE_INT8: (-(2**7), 2**7 - 1),
    M.MAV_PARAM_TYPE_UINT16: (0, 2**16 - 1), M.MAV_PARAM_TYPE_INT16: (-(2**15), 2**15 - 1),
    M.MAV_PARAM_TYPE_UINT32: (0, 2**32 - 1), M.MAV_PARAM_TYPE_INT32: (-(2**31), 2**31 - 1),
    M.MAV_PARAM_TYPE_UINT64: (0, 2**64 - 1), M.MAV_PARAM_TYPE_INT64: (-(2**63), 2**63 - 1),
}
QGC_HEADER = "# Vehicle-Id Component-Id Name Value Type"


class ParamFileError(UsageError):
    """A parameter file that cannot be used (exit code 2: nothing was sent)."""

    def __init__(self, source: str, line: int | None, reason: str):
        self.source, self.line, self.reason = source, line, reason
        super().__init__(f"{source}:{line}: {reason}" if line is not None else f"{source}: {reason}")


@dataclass(frozen=True)
class ParamLine:
    name: str
    value: float
    ptype: int | None  # MAV_PARAM_TYPE from a QGroundControl file, None from MAVProxy's
    line: int
    sysid: int | None = None
    compid: int | None = None


def fits_float32(value: float) -> bool:
    """True when ``value`` rounds to a finite float32 (3.4028235e+38, FLT_MAX's shortest decimal, does)."""
    with np.errstate(over="ignore"):
        return bool(np.isfinite(np.float32(value)))


def check_value(value: float, ptype: int | None, what: str = "value") -> str | None:
    """Why ``value`` does not fit ``ptype`` (None: it does; ``ptype`` None means REAL32)."""
    if not math.isfinite(value):
        return f"{what} {value!r} is not a finite number"
    if ptype in INT_RANGES:
        lo, hi = INT_RANGES[ptype]
        if value != int(value) or not lo <= value <= hi:
            return f"{what} {value!r} does not fit {M.enums['MAV_PARAM_TYPE'][ptype].name} ({lo}..{hi})"
        return None
    if ptype != REAL64 and not fits_float32(value):
        return f"{what} {value!r} does not fit a REAL32 (|v| <= 3.4e38)"
    return None


def _number(text: str, source: str, line: int, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ParamFileError(source, line, f"{what}: {text!r} is not a number") from None


def _int(text: str, source: str, line: int, what: str, lo: int, hi: int) -> int:
    try:
        v = int(text)
    except ValueError:
        raise ParamFileError(source, line, f"{what}: {text!r} is not a whole number") from None
    if not lo <= v <= hi:
        raise ParamFileError(source, line, f"{what}: {v} must be in {lo}..{hi}")
    return v


def _name(text: str, source: str, line: int) -> str:
    if not NAME_RE.match(text):
        raise ParamFileError(source, line, f"name {text[:40]!r}: must be 1 to 16 characters A-Z, a-z, 0-9 or _")
    return text


def parse_params(text: str, source: str = "<params>") -> list[ParamLine]:
    """Every parameter line of a QGroundControl or MAVProxy file (ParamFileError on any problem)."""
    out: list[ParamLine] = []
    seen: dict[str, int] = {}
    form = None
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = line.split()
        if form is None:
            form = "qgc" if len(fields) == 5 else "mavproxy"
        if form == "mavproxy" and len(fields) == 1 and "=" in line:
            fields = [f.strip() for f in line.split("=", 1)]
        elif form == "mavproxy" and len(fields) == 3 and fields[1] == "=":
            fields = [fields[0], fields[2]]
        if form == "qgc":
            if len(fields) != 5:
                raise ParamFileError(source, lineno, f"expected 5 fields (sysid compid name value type) like the "
                                                     f"first parameter line, got {len(fields)}")
            sysid = _int(fields[0], source, lineno, "sysid", 0, 255)
            compid = _int(fields[1], source, lineno, "compid", 0, 255)
            name = _name(fields[2], source, lineno)
            ptype = _int(fields[4], source, lineno, "type", 1, 10)
            value = _number(fields[3], source, lineno, f"{name} value")
        else:
            if len(fields) != 2:
                raise ParamFileError(source, lineno, f"expected NAME VALUE (MAVProxy) like the first parameter "
                                                     f"line, got {len(fields)} fields")
            sysid = compid = ptype = None
            name = _name(fields[0], source, lineno)
            value = _number(fields[1], source, lineno, f"{name} value")
        why = check_value(value, ptype, f"{name} value")
        if why:
            raise ParamFileError(source, lineno, why)
        if name in seen:
            raise ParamFileError(source, lineno, f"{name} is set twice (first on line {seen[name]})")
        seen[name] = lineno
        out.append(ParamLine(name, value, ptype, lineno, sysid, compid))
    if not out:
        raise ParamFileError(source, None, "no parameter lines (expected 'sysid compid name value type' or "
                                           "'NAME VALUE' lines)")
    return out


def load_params(path) -> list[ParamLine]:
    return parse_params(read_text(path, ParamFileError), str(path))


def value_text(value: float, ptype: int | None) -> str:
    """A value as the file shows it: whole numbers for integer types, the shortest decimal of
    the float32 (REAL32) or float64 (REAL64) value otherwise."""
    if not math.isfinite(value):
        return repr(float(value))  # "nan"/"inf": written as read, refused on load
    if ptype in INT_RANGES:
        return str(int(value))
    if ptype == REAL64:
        return repr(float(value))
    v = np.float32(value)
    if float(v) == int(v) and abs(v) < 1e15:
        return str(int(v))
    if 1e-5 <= abs(v) < 1e16:
        return np.format_float_positional(v, unique=True, trim="-")
    return np.format_float_scientific(v, unique=True, trim="-")


def write_params(params, sysid: int, compid: int, vehicle: str = "") -> str:
    """QGroundControl ``.params`` text of ``params`` ({name: (value, type)}), sorted by name."""
    lines = [f"# Onboard parameters for Vehicle {sysid}" + (f" ({vehicle})" if vehicle else ""), "#",
             "# Written by hilms-sil rig-gcs", "#", QGC_HEADER]
    for name in sorted(params):
        value, ptype = params[name]
        lines.append(f"{sysid}\t{compid}\t{name}\t{value_text(value, ptype)}\t{ptype}")
    return "\n".join(lines) + "\n"


def save_params(path, params, sysid: int, compid: int, vehicle: str = "") -> None:
    atomic_write_text(path, write_params(params, sysid, compid, vehicle))
