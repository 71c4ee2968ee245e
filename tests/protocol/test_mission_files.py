"""QGC .plan / QGC WPL 110 files: round trips, canonical values, and clear errors for bad input."""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from protocol.dialect import mavlink as M
from protocol.mission_files import (
    Mission, MissionFileError, MissionItem, load_mission, parse_plan, parse_wpl, save_mission, write_plan, write_wpl,
)

finite32 = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, width=32)
param = st.one_of(finite32, st.just(math.nan))


@st.composite
def items(draw):
    frame = draw(st.sampled_from([M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_LOCAL_ENU, M.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                  M.MAV_FRAME_GLOBAL, M.MAV_FRAME_MISSION]))
    if frame in (M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL):
        x = draw(st.floats(-90, 90))
        y = draw(st.floats(-180, 180))
    elif frame == M.MAV_FRAME_MISSION:
        x, y = draw(st.integers(-1000, 1000)), draw(st.integers(-1000, 1000))
    else:
        x, y = draw(st.floats(-1e4, 1e4)), draw(st.floats(-1e4, 1e4))
    cmd = draw(st.sampled_from([M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_NAV_TAKEOFF, M.MAV_CMD_NAV_LAND,
                                M.MAV_CMD_DO_CHANGE_SPEED]))
    return MissionItem(cmd, frame, tuple(draw(param) for _ in range(4)), float(x), float(y), draw(finite32),
                       draw(st.booleans()), draw(st.booleans()))


homes = st.tuples(st.floats(-90, 90), st.floats(-180, 180), st.floats(-500, 9000))
missions = st.builds(Mission, st.lists(items(), max_size=12).map(tuple), homes)


@settings(max_examples=150, deadline=None)
@given(missions)
def test_wpl_round_trip(mission):
    text = write_wpl(mission)
    back = parse_wpl(text)
    assert back.same_as(mission.canonical())
    assert write_wpl(back) == text


@settings(max_examples=150, deadline=None)
@given(missions)
def test_plan_round_trip(mission):
    plain = Mission(tuple(MissionItem(i.command, i.frame, i.params, i.x, i.y, i.z, i.autocontinue, False)
                          for i in mission.items), mission.home)
    text = write_plan(plain)
    back = parse_plan(text)
    assert back.same_as(plain.canonical())
    assert write_plan(back) == text
    json.loads(text)  # strict JSON: NaN written as null


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=300))
def test_wpl_garbage_is_a_file_error(text):
    try:
        parse_wpl("QGC WPL 110\n" + text, "g.waypoints")
    except MissionFileError as exc:
        assert str(exc).startswith("g.waypoints:")


@settings(max_examples=200, deadline=None)
@given(st.recursive(st.none() | st.booleans() | st.floats(allow_nan=False) | st.text(max_size=5),
                    lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=8), c, max_size=4),
                    max_leaves=20))
def test_plan_garbage_is_a_file_error(doc):
    try:
        parse_plan(json.dumps(doc), "g.plan")
    except MissionFileError:
        pass


@settings(max_examples=100, deadline=None)
@given(missions, st.data())
def test_wpl_bad_field_names_its_line(mission, data):
    if not mission.items:
        return
    lines = write_wpl(mission).splitlines()
    k = data.draw(st.integers(1, len(lines) - 1))
    fields = lines[k].split("\t")
    col = data.draw(st.sampled_from([0, 2, 3, 4, 8, 11]))
    fields[col] = "abc"
    lines[k] = "\t".join(fields)
    with pytest.raises(MissionFileError) as exc:
        parse_wpl("\n".join(lines), "m.waypoints")
    assert exc.value.where == k + 1


def test_wpl_errors_say_line_and_reason():
    good = "QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t35.7\t51.4\t1200\t1\n1\t0\t1\t16\t0\t0.08\t0\t0\t1\t2\t-2\t1\n"
    assert len(parse_wpl(good).items) == 1
    cases = {
        "QGC WPL 120\n": (1, "unsupported format version"),
        "hello\n": (1, "first line must be"),
        good + "2\t0\t1\t16\t0\t0\t0\t0\t1\t2\n": (4, "expected 12 fields"),
        good + "3\t0\t1\t16\t0\t0\t0\t0\t1\t2\t-2\t1\n": (4, "seq 3: expected 2"),
        good + "2\t0\t99\t16\t0\t0\t0\t0\t1\t2\t-2\t1\n": (4, "frame 99 is not a MAV_FRAME"),
        good + "2\t0\t1\t9999\t0\t0\t0\t0\t1\t2\t-2\t1\n": (4, "command 9999 is not a MAV_CMD"),
        good + "2\t0\t3\t16\t0\t0\t0\t0\t95\t2\t-2\t1\n": (4, "latitude 95.0 outside"),
        good + "2\t2\t1\t16\t0\t0\t0\t0\t1\t2\t-2\t1\n": (4, "current: 2 must be one of [0, 1]"),
        good + "2\t0\t1\t16\t0\t0\t0\t0\t1\t2\tinf\t1\n": (4, "z = inf"),
    }
    for text, (line, reason) in cases.items():
        with pytest.raises(MissionFileError) as exc:
            parse_wpl(text, "f.waypoints")
        assert exc.value.where == line, text
        assert reason in str(exc.value), str(exc.value)


def _plan(items, **extra):
    doc = {"fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
           "geoFence": {"circles": [], "polygons": [], "version": 2}, "rallyPoints": {"points": [], "version": 2},
           "mission": {"version": 2, "items": items, "plannedHomePosition": [47.39, 8.54, 488.0], "firmwareType": 12,
                       "vehicleType": 2, "cruiseSpeed": 15, "hoverSpeed": 5}}
    doc.update(extra)
    return json.dumps(doc, indent=4)


QGC_ITEM = {"AMSLAltAboveTerrain": None, "Altitude": 50, "AltitudeMode": 1, "autoContinue": True, "command": 16,
            "doJumpId": 1, "frame": 3, "params": [0, 0, 0, None, 47.3977419, 8.5455938, 50], "type": "SimpleItem"}


def test_plan_reads_qgroundcontrol_items():
    m = parse_plan(_plan([QGC_ITEM]))
    assert m.home == (47.39, 8.54, 488.0)
    it = m.items[0]
    assert (it.command, it.frame, it.x, it.y, it.z) == (16, 3, 47.3977419, 8.5455938, 50.0)
    assert math.isnan(it.params[3])
    assert m.plan_settings["firmwareType"] == 12


def test_plan_errors_name_the_field():
    bad_param = dict(QGC_ITEM, params=[0, 0, 0, None, "x", 8.5, 50])
    cases = [
        ("{\n  \"fileType\": \"Plan\",\n  oops\n}", "3", "invalid JSON"),
        (_plan([bad_param]), "mission.items[0].params[4]", "expected a number or null"),
        (_plan([{"type": "ComplexItem", "complexItemType": "survey"}]), "mission.items[0]", "'survey' is not supported"),
        (_plan([dict(QGC_ITEM, params=[0, 0, 0])]), "mission.items[0].params", "expected 7 values"),
        (_plan([QGC_ITEM], geoFence={"circles": [{"radius": 5}], "polygons": [], "version": 2}), "geoFence.circles",
         "supports missions only"),
        (_plan([QGC_ITEM], version=2), "version", "unsupported plan version"),
        (_plan([dict(QGC_ITEM, params=[0, 0, 0, 0, None, 8.5, 50])]), "mission.items[0].params[4]", "null"),
        (_plan([dict(QGC_ITEM, frame=3, params=[0, 0, 0, 0, 91.0, 8.5, 50])]), "mission.items[0]", "latitude"),
        ("[1, 2]", "fileType", "not a QGroundControl plan"),
    ]
    for text, where, reason in cases:
        with pytest.raises(MissionFileError) as exc:
            parse_plan(text, "p.plan")
        assert where in str(exc.value) and reason in str(exc.value), str(exc.value)
        assert str(exc.value).startswith("p.plan")


def test_files_by_suffix_and_atomic_save(tmp_path):
    m = Mission((MissionItem(16, 1, (0.0, 0.08, 0.0, math.nan), 1.5, -2.25, -2.0),), (35.7, 51.4, 1200.0))
    for name in ("a.plan", "a.waypoints", "a.txt"):
        path = tmp_path / name
        save_mission(m, path)
        assert load_mission(path).same_as(m.canonical())
    with pytest.raises(MissionFileError, match="unknown mission file type '.json'"):
        save_mission(m, tmp_path / "a.json")
    # a mission that cannot be written leaves the existing file untouched
    before = (tmp_path / "a.plan").read_text()
    bad = Mission((MissionItem(16, 3, (0.0, 0.0, 0.0, 0.0), 95.0, 0.0, 1.0),))
    with pytest.raises(MissionFileError):
        save_mission(bad, tmp_path / "a.plan")
    assert (tmp_path / "a.plan").read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.plan", "a.txt", "a.waypoints"]


def test_float32_extremes_survive_a_round_trip():
    """FLT_MAX is written as its shortest decimal 3.4028235e+38, a little above FLT_MAX as a float64:
    it must read back (a plain |v| <= FLT_MAX check refused the file rig-gcs had written)."""
    big = float(np.finfo(np.float32).max)
    m = Mission((MissionItem(M.MAV_CMD_NAV_WAYPOINT, M.MAV_FRAME_LOCAL_NED, (big, -big, 0.0, math.nan), 1.0, 2.0, -big),),
                (35.7, 51.4, 1200.0))
    for write, parse in ((write_wpl, parse_wpl), (write_plan, parse_plan)):
        assert parse(write(m)).same_as(m.canonical())
    with pytest.raises(MissionFileError, match="param1 = 3.5e\\+38 does not fit a float32"):
        parse_wpl(write_wpl(m).replace("3.4028235e+38", "3.5e+38", 1))


def test_a_fence_that_is_not_a_list_is_an_error_not_a_crash():
    """Found by tests/gcs_tools/test_files_fuzz.py: "circles": 1 raised a TypeError (len of an int)."""
    doc = json.loads(write_plan(Mission((), (35.7, 51.4, 1200.0))))
    doc["geoFence"]["circles"] = 1
    with pytest.raises(MissionFileError, match="geoFence.circles: expected a list, got 1"):
        parse_plan(json.dumps(doc), "f.plan")
