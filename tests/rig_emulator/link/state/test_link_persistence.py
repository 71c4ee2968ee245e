"""Parameters, the mission and the signing clock survive restarts of a real `rig-emulator serve`
process; SIGKILL at random moments (mid-upload, mid parameter storm) always leaves the old or the
new state; bad or unwritable state files give clear errors and the rig keeps what it had.

``HILMS_KILL_TRIALS`` (default 3) sets the number of SIGKILL trials."""

import hashlib
import json
import math
import os
import random
import signal
import subprocess
import sys
import threading
import time

import numpy as np

from protocol.dialect import mavlink as M
from protocol.geodesy import Home
from protocol.mission_items import MissionItem
from rig_emulator.link.mission.store import MissionStore
from rig_emulator.link.parameters.store import ParamStore
from rig_emulator.link.signing.clock import wall_timestamp
from rig_emulator.link.state.directory import StateDir
from rig_emulator.testing.rig import MissionClient, RigProcess, RigThread, connect, recv

TRIALS = int(os.environ.get("HILMS_KILL_TRIALS", "3"))
HOME = Home(35.7, 51.4, 1200.0)
KEY = hashlib.sha256(b"persist").digest()
LOCAL, GLOBAL_REL = M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def _mission(n: int, offset: int = 0) -> list:
    """Items with values as the wire carries them (float32 params and z, x/y on MISSION_ITEM_INT's grid)."""
    items = [MissionItem(seq=0, frame=GLOBAL_REL, command=M.MAV_CMD_NAV_WAYPOINT, current=1,
                         param2=float(np.float32(0.08)), param4=math.nan, x=357000123 / 1e7,
                         y=(514000456 + 10 * offset) / 1e7, z=2.0)]
    items += [MissionItem(seq=i, frame=LOCAL, command=M.MAV_CMD_NAV_WAYPOINT, param1=0.5, x=(100 * i + offset) / 1e4,
                          y=-0.25, z=-1.5) for i in range(1, n)]
    return items


def _key(item) -> tuple:
    """An item's fields as they went over the wire (NaN compared equal to NaN)."""
    return tuple("nan" if isinstance(v, float) and math.isnan(v) else v for v in item.__dict__.values())


def _stored_mission(path) -> list | None:
    d = StateDir(path)
    try:
        items = MissionStore(d, HOME).items
    finally:
        d.close()
    return None if items is None else [_key(i) for i in items]


def _stored_params(path) -> dict:
    d = StateDir(path)
    try:
        return ParamStore(d).values
    finally:
        d.close()


def _read_param(conn, name: str) -> float:
    conn.mav.param_request_read_send(1, 1, name.encode(), -1)
    return recv(conn, "PARAM_VALUE", 5, lambda m: m.param_id == name).param_value


def test_parameters_and_mission_survive_a_restart(tmp_path):
    mission = _mission(6)
    with RigProcess(speedup=2.0, state_dir=tmp_path) as rig:
        c = connect(rig.tcp_url)
        c.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.5, M.MAV_PARAM_TYPE_REAL32)
        c.mav.param_set_send(1, 1, b"WP_RADIUS", 0.1, M.MAV_PARAM_TYPE_REAL32)
        assert recv(c, "PARAM_VALUE", 5, lambda m: m.param_id == "WP_RADIUS") is not None
        client = MissionClient(c)
        assert client.upload(mission) == M.MAV_MISSION_ACCEPTED
        before = [_key(i) for i in client.download()]
        c.close()
        assert rig.stop() == 0
    with RigProcess(speedup=2.0, state_dir=tmp_path) as rig:
        assert any("restored 2 parameters (SMC_K_PHI, WP_RADIUS) and a 6-item mission" in line for line in rig.output)
        c = connect(rig.tcp_url)
        assert _read_param(c, "SMC_K_PHI") == 2.5 and _read_param(c, "WP_RADIUS") == np.float32(0.1)
        client = MissionClient(c)
        assert [_key(i) for i in client.download()] == before  # identical, NaN and the current flag included
        assert client.upload([]) == M.MAV_MISSION_ACCEPTED  # clearing is stored too
        c.close()
        assert rig.stop() == 0
    assert _stored_mission(tmp_path) == [] and _stored_params(tmp_path)["SMC_K_PHI"] == 2.5


STORM = ("SMC_K_PHI", "SMC_K_THE", "WP_RADIUS")


def _storm_value(i: int) -> float:
    return float(np.float32(0.05 + 0.001 * (i % 1000)))


def _state_after(start: dict, k: int) -> dict:
    state = dict(start)
    for i in range(k):
        state[STORM[i % 3]] = _storm_value(i)
    return state


class _Storm(threading.Thread):
    """PARAM_SETs every 5 ms, without waiting for the echoes (sent after storing), which it counts."""

    def __init__(self, url):
        super().__init__(daemon=True)
        self.conn = connect(url)
        self.sent = self.acked = 0
        self.stop = threading.Event()
        threading.Thread(target=self._read_acks, daemon=True).start()

    def _read_acks(self):
        while not self.stop.is_set():
            try:
                m = self.conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.1)
            except Exception:  # noqa: BLE001 - the connection dies with the rig
                return
            if m is not None and m.param_id in STORM:
                self.acked += 1

    def run(self):
        while not self.stop.is_set():
            i = self.sent
            try:
                self.conn.mav.param_set_send(1, 1, STORM[i % 3].encode(), _storm_value(i), M.MAV_PARAM_TYPE_REAL32)
            except OSError:
                return
            self.sent += 1
            time.sleep(0.005)  # a storm the upload can get through


class _Uploader(threading.Thread):
    """A mission upload (MissionClient) that flags when the rig has requested ``flag_after`` items,
    or has acknowledged the whole mission (``flag_after`` None)."""

    def __init__(self, url, items, flag_after: int | None):
        super().__init__(daemon=True)
        self.url, self.items, self.flag_after = url, items, flag_after
        self.flag = threading.Event()
        self.result = None

    def run(self):
        uploader = self

        class Client(MissionClient):
            requests = 0

            def _wait(self, types, condition=None):
                m = super()._wait(types, condition)
                if m is not None and m.get_type() == "MISSION_REQUEST_INT":
                    Client.requests += 1
                    if uploader.flag_after is not None and Client.requests >= uploader.flag_after:
                        uploader.flag.set()
                return m

        try:
            self.result = Client(connect(self.url), max_retries=4).upload(self.items)
            if self.flag_after is None:
                self.flag.set()
        except Exception:  # noqa: BLE001 - the rig is killed under it
            pass


def test_sigkill_mid_upload_and_mid_parameter_storm_leaves_old_or_new_state(tmp_path):
    """Trials cycle through: kill after a random number of items of an upload (the old mission must
    remain), kill just after the upload's MISSION_ACK ACCEPTED (the new one must be on disk), kill at
    a random moment of a parameter storm with an upload under way (a consistent state either way)."""
    rng = random.Random(7)
    outcomes, storms = [], []
    for trial in range(TRIALS):
        kind = ("mid-upload", "after-ack", "storm")[trial % 3]
        old_mission, old_params = _stored_mission(tmp_path), _stored_params(tmp_path)
        new = _mission(60, offset=trial)
        with RigProcess(speedup="max", state_dir=tmp_path) as rig:
            flag_after = {"mid-upload": rng.randint(1, len(new) - 1), "after-ack": None, "storm": len(new) + 1}[kind]
            uploader = _Uploader(rig.tcp_url, new, flag_after)
            uploader.start()
            storm = _Storm(rig.tcp_url) if kind == "storm" else None
            if storm is not None:
                storm.start()
                time.sleep(rng.uniform(0.05, 1.5))
            else:
                assert uploader.flag.wait(30), f"trial {trial}: the upload did not get going"
            acked = storm.acked if storm is not None else 0  # echoes counted here were sent after their write
            assert rig.stop(signal.SIGKILL) == -signal.SIGKILL
            if storm is not None:
                storm.stop.set()
                storm.join(5)
                storm.conn.close()
        mission = _stored_mission(tmp_path)  # always parses (else StateError)
        expected = {"mid-upload": [old_mission], "after-ack": [[_key(i) for i in new]],
                    "storm": [old_mission, [_key(i) for i in new]]}[kind]
        assert mission in expected, f"trial {trial} ({kind}): not the mission expected"
        outcomes.append((kind, "new" if mission != old_mission else "old"))
        stored = _stored_params(tmp_path)
        if storm is None:
            assert stored == old_params
        else:
            ks = [k for k in range(acked, storm.sent + 1) if _state_after(old_params, k) == stored]
            assert ks, f"trial {trial}: the parameters are no state between {acked} acknowledged and {storm.sent} sent"
            storms.append((storm.sent, acked, ks[0]))
    print(f"SIGKILL trials: missions {outcomes}; parameter storms (sent, acknowledged, stored) {storms}")


SERVE = ["serve", "--mavlink", "tcpin:127.0.0.1:0", "--speedup", "max", "--duration", "0.5"]


def _serve_in_process(capsys, *args) -> tuple[int, str, str]:
    """`rig-emulator serve ...` through the command line's own entry point, in this process."""
    from rig_emulator.cli import main

    rc = main([*SERVE, *args])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_bad_state_stops_the_start_with_the_file_named(tmp_path, capsys):
    (tmp_path / "mission.json").write_text('{"format": "hilms-sil mission", "version": 1, "items": [')
    p = subprocess.run([sys.executable, "-m", "rig_emulator", *SERVE, "--state-dir", str(tmp_path)],
                       capture_output=True, text=True, timeout=120)  # the real command
    assert p.returncode == 2 and f"{tmp_path / 'mission.json'}:1: invalid JSON" in p.stderr, p.stderr
    assert "--wipe" in p.stderr and (tmp_path / "mission.json").exists()  # nothing reset silently
    (tmp_path / "mission.json").unlink()
    (tmp_path / "params.json").write_text('{"format": "hilms-sil parameters", "version": 1, "params": {"SMC_K_PHI": 1e9}}')
    rc, _, err = _serve_in_process(capsys, "--state-dir", str(tmp_path))
    assert rc == 2 and f"{tmp_path / 'params.json'}: params.SMC_K_PHI: smc.k" in err, err
    holder = StateDir(tmp_path)  # this process holds the directory, as a running rig would
    rc, _, err = _serve_in_process(capsys, "--state-dir", str(tmp_path / "."))
    assert rc == 2 and f"is in use by another rig (pid {os.getpid()})" in err, err
    holder.close()
    rc, _, err = _serve_in_process(capsys, "--no-persist", "--wipe")
    assert rc == 2 and "--no-persist" in err
    rc, out, err = _serve_in_process(capsys, "--state-dir", str(tmp_path), "--wipe")
    assert rc == 0, err
    assert "wiped (params.json)" in out and not (tmp_path / "params.json").exists()


def test_unwritable_state_refuses_changes_and_keeps_what_was_stored(tmp_path):
    with RigThread(speedup=2.0, state_dir=tmp_path) as rig:
        c = connect(rig.tcp_url)
        c.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.5, M.MAV_PARAM_TYPE_REAL32)
        assert recv(c, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.5
        assert MissionClient(c).upload(_mission(3)) == M.MAV_MISSION_ACCEPTED
        for name in ("params.json", "mission.json"):  # a directory in the way: os.replace fails (even as root)
            os.rename(tmp_path / name, tmp_path / f"{name}.bak")
            (tmp_path / name).mkdir()
        c.mav.param_set_send(1, 1, b"SMC_K_PHI", 3.0, M.MAV_PARAM_TYPE_REAL32)
        assert recv(c, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.5  # undone
        assert "cannot store" in recv(c, "STATUSTEXT", 5, lambda m: "SMC_K_PHI" in m.text).text
        assert rig.server.rig.cfg["smc.k"][0] == 2.5
        assert MissionClient(c).upload(_mission(4, offset=1)) == M.MAV_MISSION_ERROR
        assert MissionClient(c).upload([]) == M.MAV_MISSION_ERROR  # clearing neither
        assert len(MissionClient(c).download()) == 3 and _read_param(c, "SMC_K_PHI") == 2.5  # the rig goes on
        c.close()
    for name in ("params.json", "mission.json"):
        (tmp_path / name).rmdir()
        os.rename(tmp_path / f"{name}.bak", tmp_path / name)
    assert _stored_params(tmp_path) == {"SMC_K_PHI": 2.5} and len(_stored_mission(tmp_path)) == 3


def test_signing_clock_and_replay_table_survive_a_restart(tmp_path):
    with RigThread(speedup=2.0, state_dir=tmp_path, signing_key=KEY) as rig:
        c = connect(rig.tcp_url, signing_key=KEY)
        buf = c.mav.param_set_encode(1, 1, b"SMC_K_PHI", 2.0, M.MAV_PARAM_TYPE_REAL32).pack(c.mav)
        c.mav.seq += 1
        c.write(buf)  # a signed packet someone records ...
        assert recv(c, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.0
        c.close()
    doc = json.loads((tmp_path / "signing.json").read_text())
    assert doc["timestamp"] >= int.from_bytes(buf[-12:-6], "little") and doc["streams"]
    ahead = wall_timestamp() + 3600 * 100_000  # a clock stored an hour ahead of this host's (a clock stepped back)
    doc["timestamp"] = ahead
    (tmp_path / "signing.json").write_text(json.dumps(doc))
    with RigThread(speedup=2.0, state_dir=tmp_path, signing_key=KEY) as rig:
        c = connect(rig.tcp_url, signing_key=KEY)
        hb = recv(c, "HEARTBEAT", 5)
        assert hb is not None and hb.get_signed() and int.from_bytes(bytes(hb._msgbuf[-12:-6]), "little") > ahead
        c.write(buf)  # ... and replays after the restart
        deadline = time.monotonic() + 5
        while rig.server.counters.dropped["replay"] < 1 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert rig.server.counters.dropped["replay"] == 1 and rig.server.rig.cfg["smc.k"][0] == 2.0
        c.close()
