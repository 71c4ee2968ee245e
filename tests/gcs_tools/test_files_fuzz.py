"""Broken mission and parameter files through rig-gcs's entry point (hypothesis): every file is
either refused with exit code 2 and one error line naming the file and the line or field, or
accepted (then rig-gcs goes on to the link, which here has no vehicle: exit 1). Never a
traceback, never anything sent for a bad file."""

import json
import re

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcs_tools.cli import main
from gcs_tools.param_files import ParamFileError, parse_params, write_params
from protocol.dialect import mavlink as M

NO_VEHICLE = ["udpout:127.0.0.1:9", "--heartbeat-timeout", "0.01"]
VALID_WPL = ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t35.7\t51.4\t1200\t1\n"
             "1\t0\t1\t16\t0\t0.08\t0\tnan\t0\t0\t-2\t1\n2\t0\t1\t16\t0\t0.08\t0\tnan\t0\t5\t-2\t1\n")
VALID_PLAN = json.dumps({
    "fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
    "geoFence": {"circles": [], "polygons": [], "version": 2}, "rallyPoints": {"points": [], "version": 2},
    "mission": {"version": 2, "cruiseSpeed": 15, "hoverSpeed": 5, "firmwareType": 0, "vehicleType": 2,
                "plannedHomePosition": [35.7, 51.4, 1200],
                "items": [{"type": "SimpleItem", "command": 16, "frame": 1, "autoContinue": True,
                           "params": [0, 0.08, 0, None, 0, 0, -2], "doJumpId": 1},
                          {"type": "SimpleItem", "command": 16, "frame": 3, "autoContinue": True,
                           "params": [0, 0.08, 0, None, 35.7, 51.4, 2], "doJumpId": 2}]},
}, indent=4)
VALID_QGC_PARAMS = "# Onboard parameters for Vehicle 1\n#\n1\t1\tSMC_K_PHI\t2.5\t9\n1\t1\tWP_RADIUS\t0.08\t9\n"
VALID_MAVPROXY = "# MAVProxy\nSMC_K_PHI 2.5\nWP_RADIUS=0.08\n"

tokens = st.sampled_from(["", "x", "nan", "inf", "-inf", "1e400", "-1", "0", "1", "3.5", "99999999999", "16",
                          "\t", " ", "#", "QGC WPL 110", "null", "{", "}", "[", "]", '"', ",", ":", "\x00", "é", "1e-50"])


@st.composite
def mutated(draw, text: str):
    """``text`` with a few random edits: characters or tokens replaced, inserted, deleted; lines
    dropped or duplicated."""
    s = text
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["replace", "insert", "delete", "dup_line", "drop_line", "char"]))
        if not s:
            s = draw(tokens)
            continue
        i = draw(st.integers(0, len(s) - 1))
        if op == "replace":
            j = draw(st.integers(i, min(len(s), i + 12)))
            s = s[:i] + draw(tokens | st.text(max_size=6)) + s[j:]
        elif op == "insert":
            s = s[:i] + draw(tokens | st.text(max_size=6)) + s[i:]
        elif op == "delete":
            s = s[:i] + s[draw(st.integers(i, min(len(s), i + 12))):]
        elif op == "char":
            s = s[:i] + draw(st.characters()) + s[i + 1:]
        else:
            lines = s.split("\n")
            k = draw(st.integers(0, len(lines) - 1))
            lines = lines[:k] + ([lines[k]] * 2 if op == "dup_line" else []) + lines[k + 1:]
            s = "\n".join(lines)
    return s


json_values = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
                           lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=8), kids, max_size=4),
                           max_leaves=12)


@st.composite
def plan_with_a_bad_value(draw):
    """The valid plan with one value somewhere replaced by arbitrary JSON."""
    doc = json.loads(VALID_PLAN)
    node, path = doc, []
    while isinstance(node, (dict, list)) and node and draw(st.booleans()):
        key = draw(st.sampled_from(sorted(node) if isinstance(node, dict) else list(range(len(node)))))
        path.append(key)
        node = node[key]
    target = doc
    for key in path[:-1]:
        target = target[key]
    if path:
        target[path[-1]] = draw(json_values)
    else:
        doc = draw(json_values)
    return json.dumps(doc)


def _file_bytes(draw_text):
    return draw_text.map(lambda t: t.encode("utf-8", "surrogatepass"))


def _run(capsys, tmp_path, args, path, data: bytes):
    path.write_bytes(data)
    code = main([*args[:2], *NO_VEHICLE[:1], str(path), *NO_VEHICLE[1:]])
    out = capsys.readouterr()
    if code == 2:
        lines = out.err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"rig-gcs: error: {path}"), out.err
        where = lines[0][len(f"rig-gcs: error: {path}"):]
        assert re.match(r"^(:\d+: |: [\w.\[\]]+: |: )\S", where), lines[0]  # :LINE: or : FIELD: or : reason
    else:
        assert code == 1 and ("no vehicle HEARTBEAT" in out.err or "link" in out.err), (code, out.err)
    return code


SLOW_OK = settings(max_examples=50, deadline=None,
                   suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@SLOW_OK
@given(data=_file_bytes(mutated(VALID_WPL)) | st.binary(max_size=300))
def test_broken_waypoint_files(capsys, tmp_path, data):
    _run(capsys, tmp_path, ["mission", "upload"], tmp_path / "m.waypoints", data)


@SLOW_OK
@given(data=_file_bytes(mutated(VALID_PLAN) | plan_with_a_bad_value()) | st.binary(max_size=300))
def test_broken_plan_files(capsys, tmp_path, data):
    _run(capsys, tmp_path, ["mission", "upload"], tmp_path / "m.plan", data)


@SLOW_OK
@given(data=_file_bytes(mutated(VALID_QGC_PARAMS) | mutated(VALID_MAVPROXY)) | st.binary(max_size=300))
def test_broken_parameter_files(capsys, tmp_path, data):
    _run(capsys, tmp_path, ["param", "load"], tmp_path / "p.params", data)


def test_the_unmutated_files_are_accepted(capsys, tmp_path):
    for name, text, args in (("m.waypoints", VALID_WPL, ["mission", "upload"]), ("m.plan", VALID_PLAN, ["mission", "upload"]),
                             ("p.params", VALID_QGC_PARAMS, ["param", "load"]), ("p.parm", VALID_MAVPROXY, ["param", "load"])):
        assert _run(capsys, tmp_path, args, tmp_path / name, text.encode()) == 1


names = st.text("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_", min_size=1, max_size=16)
real32 = st.floats(width=32, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(st.dictionaries(names, real32, min_size=1, max_size=20))
def test_saved_parameters_load_back_exactly(params):
    text = write_params({n: (v, M.MAV_PARAM_TYPE_REAL32) for n, v in params.items()}, 1, 1)
    back = parse_params(text)
    assert {p.name: np.float32(p.value) for p in back} == {n: np.float32(v) for n, v in params.items()}  # as sent
    assert all(p.ptype == M.MAV_PARAM_TYPE_REAL32 and p.sysid == 1 and p.compid == 1 for p in back)


def test_parameter_file_errors_name_the_line():
    cases = {
        "SMC_K_PHI 1\nSMC_K_PHI 2\n": "<params>:2: SMC_K_PHI is set twice (first on line 1)",
        "1\t1\tSMC_K_PHI\t1\t9\nWP_RADIUS 2\n": "<params>:2: expected 5 fields",
        "SMC_K_PHI nan\n": "<params>:1: SMC_K_PHI value nan is not a finite number",
        "1\t1\tA\t300\t1\n": "<params>:1: A value 300.0 does not fit MAV_PARAM_TYPE_UINT8",
        "1\t1\tA\t1e39\t9\n": "<params>:1: A value 1e+39 does not fit a REAL32",
        "1\t1\tA\t1\t11\n": "<params>:1: type: 11 must be in 1..10",
        "BAD-NAME 1\n": "<params>:1: name 'BAD-NAME'",
        "# only comments\n\n": "<params>: no parameter lines",
    }
    for text, message in cases.items():
        try:
            parse_params(text)
        except ParamFileError as exc:
            assert str(exc).startswith(message), (text, str(exc))
        else:
            raise AssertionError(f"accepted {text!r}")
