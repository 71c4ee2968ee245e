"""The rig's mission, stored in the state directory (``mission.json``).

Written (atomically, see :mod:`rig_emulator.link.state.directory`) when an upload completes and when the mission is
cleared, *before* the rig answers MISSION_ACK ACCEPTED; a mission that cannot be stored is
refused (MAV_MISSION_ERROR) and the previous one stays, in memory and on disk. An upload in
progress is never written, so a rig killed mid-upload restarts with the previous mission.

The items are kept exactly as the rig holds them (what a download returns, NaN and the
``current`` flag included), which a QGroundControl ``.plan`` cannot always carry (it has
no NaN positions and rounds coordinates): JSON numbers, with ``"nan"``, ``"inf"`` and
``"-inf"`` for the non-finite ones::

    {"format": "hilms-sil mission", "version": 1, "home": [35.7, 51.4, 1200.0],
     "items": [{"seq": 0, "frame": 6, "command": 16, "current": 0, "autocontinue": 1,
                "params": [0.0, 0.08, 0.0, "nan"], "x": 35.70001, "y": 51.4, "z": 2.0}]}

``home`` records the home position at the time of the upload (for the reader; the rig flies
the items about its ``--home``). For a ``.plan`` to open in QGroundControl:
``rig-gcs mission download tcp:127.0.0.1:5760 mission.plan``.
"""

from __future__ import annotations

import math

from protocol.dialect import mavlink as M
from protocol.mission_items import MissionItem, validate_item
from rig_emulator.link.state.directory import StateDir

FILE = "mission.json"
FORMAT = "hilms-sil mission"
VERSION = 1
_NONFINITE = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf}
_INT_FIELDS = {"seq": 65535, "frame": 255, "command": 65535, "current": 255, "autocontinue": 255}


def _encode(v: float):
    v = float(v)
    if math.isnan(v):
        return "nan"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


def item_document(item: MissionItem) -> dict:
    return {"seq": item.seq, "frame": item.frame, "command": item.command, "current": item.current,
            "autocontinue": item.autocontinue,
            "params": [_encode(v) for v in (item.param1, item.param2, item.param3, item.param4)],
            "x": _encode(item.x), "y": _encode(item.y), "z": _encode(item.z)}


def _number(value, state: StateDir, where: str) -> float:
    if isinstance(value, str) and value in _NONFINITE:
        return _NONFINITE[value]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise state.error(FILE, where, f"expected a number or \"nan\", got {value!r}"[:120])
    return float(value)


def parse_items(doc: dict, state: StateDir, home) -> tuple:
    """The MissionItems of a mission document, each one the rig would accept in an upload."""
    raw = doc.get("items")
    if not isinstance(raw, list):
        raise state.error(FILE, "items", "expected a list")
    items = []
    for k, it in enumerate(raw):
        where = f"items[{k}]"
        if not isinstance(it, dict):
            raise state.error(FILE, where, "expected an object")
        ints = {}
        for name, top in _INT_FIELDS.items():
            v = it.get(name)
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= top:
                raise state.error(FILE, f"{where}.{name}", f"expected a whole number in 0..{top}, got {v!r}"[:120])
            ints[name] = v
        if ints["seq"] != k:
            raise state.error(FILE, f"{where}.seq", f"{ints['seq']}: expected {k}")
        params = it.get("params")
        if not isinstance(params, list) or len(params) != 4:
            raise state.error(FILE, f"{where}.params", "expected 4 values")
        p = [_number(v, state, f"{where}.params[{i}]") for i, v in enumerate(params)]
        x, y, z = (_number(it.get(n), state, f"{where}.{n}") for n in ("x", "y", "z"))
        item = MissionItem(seq=k, frame=ints["frame"], command=ints["command"], current=ints["current"],
                           autocontinue=ints["autocontinue"], param1=p[0], param2=p[1], param3=p[2], param4=p[3],
                           x=x, y=y, z=z, mission_type=M.MAV_MISSION_TYPE_MISSION)
        result, reason = validate_item(item, home)
        if result != M.MAV_MISSION_ACCEPTED:
            raise state.error(FILE, where, f"the rig would not accept it: {reason}")
        items.append(item)
    return tuple(items)


class MissionStore:
    def __init__(self, state: StateDir, home):
        self.state = state
        doc = state.read_json(FILE, FORMAT, VERSION)
        self.items: tuple | None = None if doc is None else parse_items(doc, state, home)

    def save(self, items, home) -> None:
        """Store ``items`` (StateWriteError: the stored mission is unchanged)."""
        doc = {"format": FORMAT, "version": VERSION, "home": [home.lat_deg, home.lon_deg, home.alt_m],
               "items": [item_document(it) for it in items]}
        self.state.write_json(FILE, doc)
        self.items = tuple(items)
