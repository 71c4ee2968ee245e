"""The state directory's documents without a rig: round trips, locking, and every bad document a
clear StateError naming the file (hypothesis for the parsers)."""

import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from protocol.dialect import mavlink as M
from protocol.geodesy import Home
from protocol.mission_items import MissionItem
from rig_emulator.link.mission.store import MissionStore
from rig_emulator.link.parameters.store import ParamStore
from rig_emulator.link.state.rig_state import RigState
from rig_emulator.link.state.directory import StateDir, StateError

HOME = Home(35.7, 51.4, 1200.0)
WP = M.MAV_CMD_NAV_WAYPOINT


def _items():
    return (
        MissionItem(seq=0, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, command=WP, current=1, param2=0.07999999821186066,
                    param4=math.nan, x=35.7000123, y=51.4000456, z=2.0),
        MissionItem(seq=1, frame=M.MAV_FRAME_LOCAL_NED, command=M.MAV_CMD_NAV_LAND, x=math.nan, y=math.nan, z=0.0),
        MissionItem(seq=2, frame=M.MAV_FRAME_LOCAL_ENU, command=M.MAV_CMD_DO_CHANGE_SPEED, param2=1.5,
                    param3=math.inf, x=1.2345600128173828, y=-0.1, z=0.0),
    )


def _same(a: MissionItem, b: MissionItem) -> bool:
    fa, fb = a.__dict__, b.__dict__
    return all(fa[k] == fb[k] or (isinstance(fa[k], float) and math.isnan(fa[k]) and math.isnan(fb[k])) for k in fa)


def test_params_and_mission_round_trip_exactly(tmp_path):
    d = StateDir(tmp_path)
    ParamStore(d).save("SMC_K_PHI", 2.5)
    ParamStore(d).save("WP_RADIUS", 0.10000000149011612)
    assert ParamStore(d).values == {"SMC_K_PHI": 2.5, "WP_RADIUS": 0.10000000149011612}
    MissionStore(d, HOME).save(_items(), HOME)
    back = MissionStore(d, HOME).items
    assert len(back) == 3 and all(_same(a, b) for a, b in zip(_items(), back))
    MissionStore(d, HOME).save((), HOME)
    assert MissionStore(d, HOME).items == ()
    d.close()


def test_a_renamed_parameter_is_read_under_its_new_name(tmp_path):
    (tmp_path / "params.json").write_text(json.dumps(
        {"format": "hilms-sil parameters", "version": 1, "params": {"GUI_SPEED": 0.75}}))
    d = StateDir(tmp_path)
    store = ParamStore(d)
    assert store.values == {"MPC_XY_CRUISE": 0.75}  # served under PX4's name
    store.save("WP_RADIUS", 0.125)
    assert json.loads((tmp_path / "params.json").read_text())["params"] == {"MPC_XY_CRUISE": 0.75, "WP_RADIUS": 0.125}
    d.close()


def test_one_rig_per_directory_and_stale_temporaries_removed(tmp_path):
    (tmp_path / ".params.json.abc.tmp").write_text("half")
    first = StateDir(tmp_path)
    assert not list(tmp_path.glob(".*.tmp"))
    with pytest.raises(StateError, match=rf"{tmp_path} is in use by another rig \(pid \d+\)"):
        StateDir(tmp_path)
    first.close()
    StateDir(tmp_path).close()


@pytest.mark.parametrize("name, text, words", [
    ("params.json", "{\"format\": \"hilms-sil parameters\", ", "invalid JSON"),
    ("params.json", "{\"format\": \"something else\", \"version\": 1}", "not a 'hilms-sil parameters' document"),
    ("params.json", "{\"format\": \"hilms-sil parameters\", \"version\": 7, \"params\": {}}", "unsupported version 7"),
    ("params.json", "{\"format\": \"hilms-sil parameters\", \"version\": 1, \"params\": {\"NOPE\": 1}}",
     "params.NOPE: no such parameter"),
    ("params.json", "{\"format\": \"hilms-sil parameters\", \"version\": 1, \"params\": {\"SMC_K_PHI\": NaN}}",
     "NaN is not valid JSON"),
    ("mission.json", "{\"format\": \"hilms-sil mission\", \"version\": 1, \"items\": [{\"seq\": 0}]}",
     "items[0].frame"),
    ("mission.json", json.dumps({"format": "hilms-sil mission", "version": 1, "items": [
        {"seq": 0, "frame": 3, "command": 16, "current": 0, "autocontinue": 1, "params": [0, 0, 0, 0],
         "x": 95.0, "y": 0, "z": 1}]}), "the rig would not accept it: item 0: latitude 95"),
    ("signing.json", "{\"format\": \"hilms-sil signing\", \"version\": 1, \"timestamp\": -5}", "timestamp"),
    ("mission.json", "\x00\xff", "not UTF-8"),
])
def test_bad_documents_name_the_file(tmp_path, name, text, words):
    (tmp_path / name).write_bytes(text.encode("latin-1"))
    with pytest.raises(StateError) as err:
        RigState(tmp_path, HOME)
    msg = str(err.value)
    assert str(tmp_path / name) in msg and words in msg and "--wipe" in msg
    StateDir(tmp_path).close()  # the failed open released its lock
    state = RigState(tmp_path, HOME, wipe=True)  # --wipe discards it
    assert state.wiped == [name] and not (tmp_path / name).exists()
    state.close()


json_values = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=8),
                           lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=10), kids, max_size=4),
                           max_leaves=12)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(params=st.dictionaries(st.sampled_from(["SMC_K_PHI", "WP_RADIUS", "X", ""]), json_values, max_size=3),
       items=st.lists(st.dictionaries(st.sampled_from(["seq", "frame", "command", "current", "autocontinue",
                                                       "params", "x", "y", "z"]), json_values), max_size=3))
def test_documents_parse_or_fail_cleanly(tmp_path, params, items):
    (tmp_path / "params.json").write_text(json.dumps({"format": "hilms-sil parameters", "version": 1, "params": params}))
    (tmp_path / "mission.json").write_text(json.dumps({"format": "hilms-sil mission", "version": 1, "items": items}))
    try:
        state = RigState(tmp_path, HOME)
    except StateError as exc:
        assert str(tmp_path) in str(exc)
    else:
        assert set(state.params.values) <= {"SMC_K_PHI", "WP_RADIUS"}
        assert len(state.mission.items) == len(items)
        state.close()


WRITER = """
import sys
from rig_emulator.link.state.directory import StateDir
d = StateDir(sys.argv[1])
i = int(sys.argv[2])


def write():
    d.write_json("doc.json", {"format": "t", "version": 1, "n": i, "pad": [i] * 20000, "end": i})


write()  # one whole version before the kill can come (a loaded machine may not run the loop at all)
print("ready", flush=True)
while True:
    i += 1
    write()
"""


def test_sigkill_while_writing_leaves_a_whole_document(tmp_path):
    """A process that does nothing but rewrite a 100 kB document, killed at random moments: the
    document is always whole (one version, never a mix), and the next open removes its temporaries."""
    import random
    import signal
    import subprocess
    import sys
    import time

    rng = random.Random(3)
    last = 0
    for trial in range(8):
        proc = subprocess.Popen([sys.executable, "-c", WRITER, str(tmp_path), str(last)], stdout=subprocess.PIPE, text=True)
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(rng.uniform(0.02, 0.3))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        d = StateDir(tmp_path)
        doc = d.read_json("doc.json", "t", 1)
        assert not list(tmp_path.glob(".*.tmp"))
        d.close()
        assert doc is not None and doc["n"] == doc["end"] and doc["pad"] == [doc["n"]] * 20000
        assert doc["n"] >= last
        last = doc["n"]
