"""Mission files: QGroundControl ``.plan`` JSON and the ``QGC WPL 110`` text format.

Both formats hold MAVLink mission items (``MAV_CMD`` + ``MAV_FRAME`` + seven parameters);
:class:`Mission` keeps them as MAVLink carries them, plus the home position the files store
next to the items:

* **QGC WPL 110** (QGroundControl, MAVProxy, Mission Planner): a header line ``QGC WPL 110``
  then one line per item, twelve whitespace-separated fields
  ``seq current frame command param1 param2 param3 param4 x y z autocontinue``. Line 0
  (``seq`` 0) is the home position (x = latitude, y = longitude, z = altitude AMSL); lines
  1..N are the mission items 0..N-1 (the rig flies item 0 too, see the project README).
* **QGC .plan** (JSON, ``fileType`` "Plan"): ``mission.items`` are ``SimpleItem`` objects
  mapped 1:1 to mission items (``params`` holds param1..4, x, y, z; ``null`` is NaN) and
  ``mission.plannedHomePosition`` is ``[lat, lon, alt]``. Complex items (surveys, corridor
  scans), geofences and rally points are rejected: the rig has no use for them and
  silently dropping them would fly something else than the file says.

Values are written in their MAVLink representation so that a file survives an upload and a
download unchanged: ``param1..4`` and ``z`` as the shortest decimal of their float32 value;
``x``/``y`` at MISSION_ITEM_INT resolution (1e-7 degree in global frames, 1e-4 m in local
frames, whole numbers in other frames); the home position at HOME_POSITION resolution
(1e-7 degree, millimetres). ``write_*(parse_*(text))`` reproduces a file this module wrote
byte for byte.

Every problem found while reading raises :class:`MissionFileError` naming the file, the
line (WPL; JSON syntax errors) or the JSON field (.plan), and the reason. Writing goes to a
temporary file in the target directory that replaces the target at the end
(:func:`save_mission`), so an existing file is never left half-written.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from protocol.atomic_file import atomic_write_text
from protocol.dialect import mavlink as M
from protocol.text_file import read_text

WPL_HEADER = "QGC WPL 110"
WPL_SUFFIXES = (".waypoints", ".txt")
PLAN_SUFFIXES = (".plan",)

GLOBAL_FRAMES = frozenset({
    M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_INT,
    M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_FRAME_GLOBAL_TERRAIN_ALT, M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
})
LOCAL_FRAMES = frozenset({
    M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_LOCAL_ENU, M.MAV_FRAME_LOCAL_OFFSET_NED, M.MAV_FRAME_BODY_NED,
    M.MAV_FRAME_BODY_OFFSET_NED, M.MAV_FRAME_BODY_FRD, M.MAV_FRAME_LOCAL_FRD, M.MAV_FRAME_LOCAL_FLU,
})
KNOWN_FRAMES = frozenset(k for k, e in M.enums["MAV_FRAME"].items() if not e.name.endswith("ENUM_END"))
KNOWN_COMMANDS = frozenset(k for k, e in M.enums["MAV_CMD"].items() if not e.name.endswith("ENUM_END"))
HOME_LATLON_SCALE = 1e7
HOME_ALT_SCALE = 1e3
INT32 = (-(2**31), 2**31 - 1)


class MissionFileError(ValueError):
    """A mission file that cannot be read (or a mission that cannot be written)."""

    def __init__(self, source: str, where: str | int | None, reason: str):
        self.source, self.where, self.reason = source, where, reason
        if where is None:
            text = f"{source}: {reason}"
        elif isinstance(where, int):
            text = f"{source}:{where}: {reason}"
        else:
            text = f"{source}: {where}: {reason}"
        super().__init__(text)


def xy_scale(frame: int) -> float:
    """MISSION_ITEM_INT's integer scale of x/y in ``frame`` (1e7 global, 1e4 local, else 1)."""
    if frame in GLOBAL_FRAMES:
        return 1e7
    if frame in LOCAL_FRAMES:
        return 1e4
    return 1.0


def f32(value: float) -> float:
    """``value`` as MAVLink carries it in a float field: the shortest decimal of its float32
    value, read back as a Python float (NaN stays NaN). Files show exactly this decimal."""
    return float(_num32(value))


def quantize(value: float, scale: float) -> float:
    """``value`` at the resolution of an int32 field scaled by ``scale``."""
    return round(value * scale) / scale


@dataclass(frozen=True)
class MissionItem:
    """One MAVLink mission item (MISSION_ITEM_INT's fields; x/y in degrees or metres)."""

    command: int
    frame: int
    params: tuple = (0.0, 0.0, 0.0, 0.0)  # param1..param4, NaN allowed
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    autocontinue: bool = True
    current: bool = False

    def canonical(self) -> "MissionItem":
        """This item as MAVLink carries it (float32 params and z, int32-scaled x/y)."""
        s = xy_scale(self.frame)
        return MissionItem(self.command, self.frame, tuple(f32(p) for p in self.params),
                           quantize(self.x, s), quantize(self.y, s), f32(self.z), bool(self.autocontinue),
                           bool(self.current))

    def same_as(self, other: "MissionItem") -> bool:
        """Equal field by field, NaN equal to NaN."""
        a = (*self.params, self.x, self.y, self.z)
        b = (*other.params, other.x, other.y, other.z)
        same = all((u == v) or (math.isnan(u) and math.isnan(v)) for u, v in zip(a, b))
        return same and (self.command, self.frame, self.autocontinue, self.current) == (
            other.command, other.frame, other.autocontinue, other.current)


@dataclass(frozen=True)
class Mission:
    """Mission items and the home position the file stores with them."""

    items: tuple = ()
    home: tuple | None = None  # (lat_deg, lon_deg, alt_m AMSL)
    plan_settings: dict = field(default_factory=dict, compare=False)  # .plan cruiseSpeed/hoverSpeed/...

    def canonical(self) -> "Mission":
        home = None
        if self.home is not None:
            lat, lon, alt = self.home
            home = (quantize(lat, HOME_LATLON_SCALE), quantize(lon, HOME_LATLON_SCALE), quantize(alt, HOME_ALT_SCALE))
        return Mission(tuple(i.canonical() for i in self.items), home, dict(self.plan_settings))

    def same_as(self, other: "Mission") -> bool:
        return (len(self.items) == len(other.items) and self.home == other.home
                and all(a.same_as(b) for a, b in zip(self.items, other.items)))


# --- value checks shared by both formats ---------------------------------------------------------------------

def _fits_float32(v: float) -> bool:
    """True when ``v`` rounds to a finite float32 (so 3.4028235e+38, FLT_MAX as written, does)."""
    with np.errstate(over="ignore"):
        return bool(np.isfinite(np.float32(v)))


def _check_item(item: MissionItem, source: str, where) -> MissionItem:
    if item.frame not in KNOWN_FRAMES:
        raise MissionFileError(source, where, f"frame {item.frame} is not a MAV_FRAME")
    if item.command not in KNOWN_COMMANDS:
        raise MissionFileError(source, where, f"command {item.command} is not a MAV_CMD")
    for name, v in zip(("param1", "param2", "param3", "param4"), item.params):
        if not (math.isnan(v) or _fits_float32(v)):
            raise MissionFileError(source, where, f"{name} = {v!r} does not fit a float32")
    if not _fits_float32(item.z):
        raise MissionFileError(source, where, f"z = {item.z!r}: must be a finite float32")
    scale = xy_scale(item.frame)
    for name, v in (("x", item.x), ("y", item.y)):
        if not math.isfinite(v):
            raise MissionFileError(source, where, f"{name} = {v!r}: must be finite")
        if not INT32[0] <= round(v * scale) <= INT32[1]:
            raise MissionFileError(source, where, f"{name} = {v!r} does not fit MISSION_ITEM_INT (int32 x {scale:g})")
    if item.frame in GLOBAL_FRAMES:
        if not -90.0 <= item.x <= 90.0:
            raise MissionFileError(source, where, f"latitude {item.x!r} outside [-90, 90]")
        if not -180.0 <= item.y <= 180.0:
            raise MissionFileError(source, where, f"longitude {item.y!r} outside [-180, 180]")
    return item


def _check_home(home, source: str, where):
    lat, lon, alt = home
    if not all(math.isfinite(v) for v in home):
        raise MissionFileError(source, where, f"home position {list(home)} must be finite")
    if not -90.0 <= lat <= 90.0 or not -180.0 <= lon <= 180.0:
        raise MissionFileError(source, where, f"home position latitude {lat!r} / longitude {lon!r} out of range")
    if abs(alt) > 1e6:
        raise MissionFileError(source, where, f"home altitude {alt!r} m out of range")
    return (float(lat), float(lon), float(alt))


# --- number formatting -------------------------------------------------------------------------------------------

def _num(v: float) -> str:
    """Shortest decimal that reads back as ``v`` ("nan" for NaN)."""
    if math.isnan(v):
        return "nan"
    if v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return repr(float(v))


def _num32(v: float) -> str:
    """Shortest decimal of the float32 value of ``v``."""
    if math.isnan(v):
        return "nan"
    v32 = np.float32(v)
    if float(v32) == int(v32) and abs(v32) < 1e15:
        return str(int(v32))
    return np.format_float_positional(v32, unique=True, trim="-") if 1e-6 <= abs(v32) < 1e16 else \
        np.format_float_scientific(v32, unique=True, trim="-")


def _json_num(v: float):
    """A JSON value for a float: None for NaN, int when whole (as QGroundControl writes)."""
    if math.isnan(v):
        return None
    if v == int(v) and abs(v) < 1e15:
        return int(v)
    return v


def _json32(v: float):
    if math.isnan(v):
        return None
    text = _num32(v)
    return int(text) if text.lstrip("-").isdigit() else float(text)


# --- QGC WPL 110 -------------------------------------------------------------------------------------------------------

def _wpl_float(text: str, source: str, line: int, name: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise MissionFileError(source, line, f"{name}: {text!r} is not a number") from None


def _wpl_int(text: str, source: str, line: int, name: str, allowed=None) -> int:
    try:
        v = int(text)
    except ValueError:
        try:
            f = float(text)
        except ValueError:
            f = math.nan
        if not (math.isfinite(f) and f == int(f)):
            raise MissionFileError(source, line, f"{name}: {text!r} is not a whole number") from None
        v = int(f)
    if allowed is not None and v not in allowed:
        raise MissionFileError(source, line, f"{name}: {v} must be one of {sorted(allowed)}")
    return v


WPL_FIELDS = ("seq", "current", "frame", "command", "param1", "param2", "param3", "param4", "x", "y", "z",
              "autocontinue")


def parse_wpl(text: str, source: str = "<wpl>") -> Mission:
    """Read a ``QGC WPL 110`` file: line 0 is home, lines 1..N are items 0..N-1."""
    lines = text.splitlines()
    if not lines or lines[0].strip() != WPL_HEADER:
        first = lines[0].strip() if lines else ""
        if first.startswith("QGC WPL"):
            raise MissionFileError(source, 1, f"unsupported format version {first!r}; expected {WPL_HEADER!r}")
        raise MissionFileError(source, 1, f"not a waypoint file: the first line must be {WPL_HEADER!r}, got {first[:40]!r}")
    home = None
    items = []
    expected_seq = 0
    for lineno, raw in enumerate(lines[1:], start=2):
        line = raw.strip()
        if not line:
            continue
        fields = line.split()
        if len(fields) != len(WPL_FIELDS):
            raise MissionFileError(source, lineno, f"expected {len(WPL_FIELDS)} fields "
                                                   f"({' '.join(WPL_FIELDS)}), got {len(fields)}")
        seq = _wpl_int(fields[0], source, lineno, "seq")
        if seq != expected_seq:
            raise MissionFileError(source, lineno, f"seq {seq}: expected {expected_seq} (items must be numbered 0, 1, 2, ...)")
        current = _wpl_int(fields[1], source, lineno, "current", (0, 1))
        frame = _wpl_int(fields[2], source, lineno, "frame")
        command = _wpl_int(fields[3], source, lineno, "command")
        params = tuple(_wpl_float(fields[4 + i], source, lineno, f"param{i + 1}") for i in range(4))
        x = _wpl_float(fields[8], source, lineno, "x")
        y = _wpl_float(fields[9], source, lineno, "y")
        z = _wpl_float(fields[10], source, lineno, "z")
        auto = _wpl_int(fields[11], source, lineno, "autocontinue", (0, 1))
        if seq == 0:
            home = _check_home((x, y, z), source, lineno)
        else:
            items.append(_check_item(MissionItem(command, frame, params, x, y, z, bool(auto), bool(current)),
                                     source, lineno))
        expected_seq += 1
    return Mission(tuple(items), home)


def write_wpl(mission: Mission) -> str:
    """The ``QGC WPL 110`` text of ``mission`` (home (0, 0, 0) when it has none)."""
    lat, lon, alt = mission.home if mission.home is not None else (0.0, 0.0, 0.0)
    out = [WPL_HEADER,
           "\t".join(["0", "1", str(M.MAV_FRAME_GLOBAL), str(M.MAV_CMD_NAV_WAYPOINT), "0", "0", "0", "0",
                      _num(quantize(lat, HOME_LATLON_SCALE)), _num(quantize(lon, HOME_LATLON_SCALE)),
                      _num(quantize(alt, HOME_ALT_SCALE)), "1"])]
    for seq, item in enumerate(mission.items, start=1):
        _check_item(item, "<mission>", f"item {seq - 1}")
        s = xy_scale(item.frame)
        out.append("\t".join([str(seq), str(int(item.current)), str(item.frame), str(item.command),
                              *(_num32(p) for p in item.params), _num(quantize(item.x, s)), _num(quantize(item.y, s)),
                              _num32(item.z), str(int(item.autocontinue))]))
    return "\n".join(out) + "\n"


# --- QGC .plan -------------------------------------------------------------------------------------------------------------

PLAN_DEFAULTS = {"cruiseSpeed": 15, "hoverSpeed": 5, "firmwareType": M.MAV_AUTOPILOT_GENERIC,
                 "vehicleType": M.MAV_TYPE_QUADROTOR, "globalPlanAltitudeMode": 1}
ALTITUDE_MODE_RELATIVE, ALTITUDE_MODE_ABSOLUTE = 1, 2


def _json_line_of(err: json.JSONDecodeError) -> int:
    return err.lineno


def _plan_number(value, source: str, where: str, allow_null: bool = False) -> float:
    if value is None and allow_null:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        kind = "a number or null" if allow_null else "a number"
        raise MissionFileError(source, where, f"expected {kind}, got {json.dumps(value)[:40]}")
    return float(value)


def _plan_int(value, source: str, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value):
        raise MissionFileError(source, where, f"expected a whole number, got {json.dumps(value)[:40]}")
    return int(value)


def _require(obj, key: str, kind, source: str, where: str):
    if not isinstance(obj, dict) or key not in obj:
        raise MissionFileError(source, where, f"missing {key!r}")
    value = obj[key]
    if not isinstance(value, kind):
        name = kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)
        raise MissionFileError(source, f"{where}.{key}" if where else key, f"expected {name}, got {json.dumps(value)[:40]}")
    return value


def parse_plan(text: str, source: str = "<plan>") -> Mission:
    """Read a QGroundControl ``.plan`` file (SimpleItems only)."""
    try:
        doc = json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(
            ValueError(f"{c} is not valid JSON (QGroundControl writes null)")))
    except json.JSONDecodeError as exc:
        raise MissionFileError(source, _json_line_of(exc), f"invalid JSON: {exc.msg} (column {exc.colno})") from None
    except ValueError as exc:
        raise MissionFileError(source, None, f"invalid JSON: {exc}") from None
    if not isinstance(doc, dict) or doc.get("fileType") != "Plan":
        raise MissionFileError(source, "fileType", "not a QGroundControl plan (fileType must be \"Plan\")")
    version = doc.get("version")
    if version != 1:
        raise MissionFileError(source, "version", f"unsupported plan version {json.dumps(version)}; expected 1")
    mission = _require(doc, "mission", dict, source, "")
    mversion = mission.get("version")
    if mversion != 2:
        raise MissionFileError(source, "mission.version", f"unsupported mission version {json.dumps(mversion)}; expected 2")
    for section, keys in (("geoFence", ("polygons", "circles")), ("rallyPoints", ("points",))):
        sec = doc.get(section)
        if sec is None:
            continue
        if not isinstance(sec, dict):
            raise MissionFileError(source, section, "expected an object")
        for key in keys:
            if key in sec and not isinstance(sec[key], list):
                raise MissionFileError(source, f"{section}.{key}", f"expected a list, got {json.dumps(sec[key])[:40]}")
            if sec.get(key):
                raise MissionFileError(source, f"{section}.{key}",
                                       f"{len(sec[key])} {section} {key} given; the rig supports missions only "
                                       f"(remove them in QGroundControl)")
    home = None
    if "plannedHomePosition" in mission:
        hp = mission["plannedHomePosition"]
        if not isinstance(hp, list) or len(hp) != 3:
            raise MissionFileError(source, "mission.plannedHomePosition", "expected [latitude, longitude, altitude]")
        home = _check_home(tuple(_plan_number(v, source, f"mission.plannedHomePosition[{i}]") for i, v in enumerate(hp)),
                           source, "mission.plannedHomePosition")
    raw_items = _require(mission, "items", list, source, "mission")
    items = []
    for k, it in enumerate(raw_items):
        where = f"mission.items[{k}]"
        if not isinstance(it, dict):
            raise MissionFileError(source, where, "expected an object")
        kind = it.get("type")
        if kind == "ComplexItem":
            raise MissionFileError(source, where, f"complex item {it.get('complexItemType', '?')!r} is not supported; "
                                                  f"the rig flies simple mission items only")
        if kind != "SimpleItem":
            raise MissionFileError(source, f"{where}.type", f"unsupported item type {json.dumps(kind)}")
        command = _plan_int(_require(it, "command", (int, float), source, where), source, f"{where}.command")
        frame = _plan_int(_require(it, "frame", (int, float), source, where), source, f"{where}.frame")
        params = _require(it, "params", list, source, where)
        if len(params) != 7:
            raise MissionFileError(source, f"{where}.params", f"expected 7 values, got {len(params)}")
        p = [_plan_number(v, source, f"{where}.params[{i}]", allow_null=True) for i, v in enumerate(params)]
        for i in (4, 5, 6):
            if math.isnan(p[i]):
                if frame in GLOBAL_FRAMES or frame in LOCAL_FRAMES:
                    raise MissionFileError(source, f"{where}.params[{i}]", "position must be a number, got null")
                p[i] = 0.0
        auto = it.get("autoContinue", True)
        if not isinstance(auto, bool):
            raise MissionFileError(source, f"{where}.autoContinue", f"expected true or false, got {json.dumps(auto)}")
        items.append(_check_item(MissionItem(command, frame, tuple(p[:4]), p[4], p[5], p[6], auto, False),
                                 source, where))
    settings = {k: mission[k] for k in PLAN_DEFAULTS if k in mission}
    return Mission(tuple(items), home, settings)


def write_plan(mission: Mission) -> str:
    """The QGroundControl ``.plan`` JSON of ``mission`` (home [0, 0, 0] when it has none)."""
    settings = dict(PLAN_DEFAULTS)
    settings.update({k: v for k, v in mission.plan_settings.items() if k in PLAN_DEFAULTS})
    items = []
    for k, item in enumerate(mission.items):
        _check_item(item, "<mission>", f"item {k}")
        s = xy_scale(item.frame)
        z = _json32(item.z)
        items.append({
            "AMSLAltAboveTerrain": None,
            "Altitude": z,
            "AltitudeMode": ALTITUDE_MODE_RELATIVE if item.frame in (M.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                                                     M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
            else ALTITUDE_MODE_ABSOLUTE,
            "autoContinue": bool(item.autocontinue),
            "command": int(item.command),
            "doJumpId": k + 1,
            "frame": int(item.frame),
            "params": [*(_json32(p) for p in item.params), _json_num(quantize(item.x, s)),
                       _json_num(quantize(item.y, s)), z],
            "type": "SimpleItem",
        })
    lat, lon, alt = mission.home if mission.home is not None else (0.0, 0.0, 0.0)
    doc = {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "hilms-sil rig-gcs",
        "mission": {
            **settings,
            "items": items,
            "plannedHomePosition": [_json_num(quantize(lat, HOME_LATLON_SCALE)), _json_num(quantize(lon, HOME_LATLON_SCALE)),
                                    _json_num(quantize(alt, HOME_ALT_SCALE))],
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }
    return json.dumps(doc, indent=4, sort_keys=True, allow_nan=False) + "\n"


# --- files by suffix ---------------------------------------------------------------------------------------------------------

def file_format(path) -> str:
    """'plan' or 'wpl' from the file suffix (MissionFileError otherwise)."""
    suffix = Path(path).suffix.lower()
    if suffix in PLAN_SUFFIXES:
        return "plan"
    if suffix in WPL_SUFFIXES:
        return "wpl"
    raise MissionFileError(str(path), None, f"unknown mission file type {suffix!r}: use .plan (QGroundControl) "
                                            f"or .waypoints/.txt (QGC WPL 110)")


def load_mission(path) -> Mission:
    """Read a .plan or WPL file (chosen by suffix)."""
    kind = file_format(path)
    text = read_text(path, MissionFileError)
    return parse_plan(text, str(path)) if kind == "plan" else parse_wpl(text, str(path))


def mission_text(mission: Mission, path) -> str:
    return write_plan(mission) if file_format(path) == "plan" else write_wpl(mission)


def save_mission(mission: Mission, path) -> None:
    """Write ``mission`` as .plan or WPL (by suffix), atomically."""
    atomic_write_text(path, mission_text(mission, path))
