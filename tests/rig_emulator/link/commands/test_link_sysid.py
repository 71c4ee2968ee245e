"""The identification flight served (MAV_CMD_HILMS_SYSID, mode AUTO.SYSID, the mission item), on the default
`hilms` plant over real sockets: a pymavlink ground station asks for the rows the identification needs,
records its own .tlog, arms, starts the flight and waits for its end in simulated time, and `rig-gcs identify`
recovers the rig's centre of gravity from that log; the refusals, the stops and the mission item.

The 120 s programme is flown once for the module (a rig process at 20x real time, about 8 s of wall time);
`--chunk-ms 1.25` gives it the 5 ms chunks a rig serving in real time runs, so the streams run at the 100 Hz
the headless export writes (at 20x the default chunk is 20 ms: 50 Hz at most)."""

import json
import math
import time

import numpy as np
import pytest

from gcs_tools.cli import main
from gcs_tools.identify.sysid_log import read_sysid_log
from protocol.dialect import mavlink as M
from protocol.mission_items import MissionItem
from rig_emulator.config.loader import load_config
from rig_emulator.guidance.sysid import DURATION_S, PARTS
from rig_emulator.link.commands import modes as MD
from rig_emulator.link.serve import prepare_rig
from rig_emulator.link.server import RigServer
from rig_emulator.testing.rig import (NAN, MissionClient, RigProcess, capture_channel, command, connect, recv,
                                      recv_text, stamp_s)

ACCEPTED, DENIED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED
SYSID_MODE = MD.custom_mode(MD.AUTO, MD.AUTO_SYSID)
LOITER = MD.custom_mode(MD.AUTO, MD.AUTO_LOITER)
ARMED = M.MAV_MODE_FLAG_SAFETY_ARMED
#: the rig's centre of gravity, far from the hilms preset's [8, -8, 35] mm the identification starts from
COG = [-0.009, 0.007, 0.035]
ROWS = (M.MAVLINK_MSG_ID_ATTITUDE, M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW, M.MAVLINK_MSG_ID_HILMS_LOAD_CELLS)
ROW_INTERVAL_US = 10_000  # 100 Hz, the headless export's rate (sim.log_rate_hz)
FLIGHT_GUARD_S = 300.0  # wall-clock bound on the flight (a guard, not a measure: the rig may run slower)


def _text(m) -> str:
    return m.text if isinstance(m.text, str) else m.text.decode("ascii", "replace")


def _attitude_target(conn, roll_deg: float) -> None:
    """A SET_ATTITUDE_TARGET (roll, hover-ish thrust) as an offboard script streams it."""
    half = math.radians(roll_deg) / 2.0
    conn.mav.set_attitude_target_send(0, 1, 1, 0, [math.cos(half), math.sin(half), 0.0, 0.0], 0.0, 0.0, 0.0, 0.6)


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """The identification flight flown once from a pymavlink ground station that logs it."""
    d = tmp_path_factory.mktemp("sysid")
    tlog = d / "gcs.tlog"
    wall0 = time.monotonic()
    args = ["--set", f"joint.cog_offset={COG}", "--chunk-ms", "1.25"]
    with RigProcess(speedup=20, args=args) as rig:
        conn = connect(rig.tcp_url)
        conn.setup_logfile(str(tlog), mode="wb")  # the ground station's own log, as MAVProxy keeps it
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert recv(conn, "HEARTBEAT", 30) is not None
        for msg_id in ROWS:
            assert command(conn, M.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, ROW_INTERVAL_US).result == ACCEPTED
        _attitude_target(conn, 25.0)  # a stale offboard set-point: stored, never flown, never missed
        assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
        conn.mav.command_long_send(1, 1, M.MAV_CMD_HILMS_SYSID, 0, 1, *[0.0] * 6)  # as MAVProxy's `long 58103 1`
        flight_wall0 = time.monotonic()
        acks, texts, beats = [], [], []
        t_start = t_last = t_done = None
        sent_midway = False
        while t_done is None and time.monotonic() - flight_wall0 < FLIGHT_GUARD_S:
            m = conn.recv_match(blocking=True, timeout=0.5)
            if m is None:
                continue
            kind = m.get_type()
            if kind == "COMMAND_ACK":
                acks.append((m.command, m.result))
            elif kind == "ATTITUDE" and acks:
                t_last = stamp_s(m)
                t_start = t_last if t_start is None else t_start
                if not sent_midway and t_last - t_start > 20.0:  # the pitch chirp
                    _attitude_target(conn, -25.0)  # a set-point streamed meanwhile: stored only
                    sent_midway = True
            elif kind == "HEARTBEAT" and m.get_srcSystem() == 1 and acks:
                beats.append((m.custom_mode, m.base_mode))
            elif kind == "STATUSTEXT":
                texts.append(_text(m))
                if texts[-1].startswith(("sysid: done", "sysid: stopped")):
                    t_done = t_last
        assert acks == [(M.MAV_CMD_HILMS_SYSID, ACCEPTED)] and t_done is not None, (acks, texts)
        flight_wall = time.monotonic() - flight_wall0
        after = recv(conn, "HEARTBEAT", 10, lambda m: m.get_srcSystem() == 1 and m.custom_mode != SYSID_MODE)
        end = time.monotonic() + 5.0
        while time.monotonic() < end:  # one more simulated second of rows after the end
            m = conn.recv_match(type="ATTITUDE", blocking=True, timeout=0.5)
            if m is not None and stamp_s(m) > t_done + 1.0:
                break
        conn.logfile.close()
        conn.close()
    js = d / "gcs.json"
    wall_id = time.monotonic()
    assert main(["identify", "--tlog", str(tlog), "--json", str(js)]) == 0
    doc = json.loads(js.read_text())
    return {"tlog": tlog, "texts": texts, "beats": beats, "after": after, "t_start": t_start, "t_done": t_done,
            "estimates": {e["key"]: e for e in doc["estimates"]}, "doc": doc, "flight_wall_s": flight_wall,
            "identify_wall_s": time.monotonic() - wall_id, "fixture_wall_s": time.monotonic() - wall0}


def test_the_flight_runs_its_parts_in_the_sysid_mode_and_ends_disarmed(flown):
    texts = flown["texts"]
    assert texts[0] == f"sysid: identification flight started ({DURATION_S:g} s)"
    assert texts[-1] == f"sysid: done ({DURATION_S:g} s), disarmed"
    announced = [t for t in texts if t.startswith(tuple(f"sysid: {name} (" for name, _, _ in PARTS))]
    assert announced == [f"sysid: {name} ({a:g}-{b:g} s)" for name, a, b in PARTS]
    # the stale set-point and the one streamed meanwhile were never flown, their loss never acted on
    assert not [t for t in texts if "offboard" in t or "stopped" in t], texts
    # the programme's length in simulated time from the start to the end (ATTITUDE stamps of 10 ms rows)
    assert flown["t_done"] - flown["t_start"] == pytest.approx(DURATION_S, abs=0.05)
    assert flown["beats"] and all(mode == SYSID_MODE for mode, _ in flown["beats"])
    assert flown["after"].custom_mode == LOITER and not flown["after"].base_mode & ARMED  # hanging, disarmed


def test_the_ground_stations_log_identifies_the_rig(flown):
    log = read_sysid_log(flown["tlog"], load_config("hilms")["motors.voltage_max"])
    assert log.dt == pytest.approx(0.01)  # rows at 100 Hz: the three messages of each row share their stamp
    t = log.t - flown["t_start"]  # the programme's time, within a row
    assert ((t >= 0.0) & (t <= DURATION_S)).sum() >= 0.99 * DURATION_S / 0.01
    # it disarmed and re-armed itself: motors at 0 V in the swings' disarmed stretches only (each swing holds
    # its tilt armed for 3.5 s, the yaw swing for 6 s, then disarms)
    start = {name: a for name, a, _ in PARTS}
    r, p, y = start["roll swing"], start["pitch swing"], start["yaw swing"]
    for a, b, armed in ((0.2, r + 3.3, True), (r + 3.7, p - 0.2, False), (p + 1.2, p + 3.3, True),
                        (p + 3.7, y - 0.2, False), (y + 1.2, y + 5.8, True), (y + 6.2, DURATION_S - 0.2, False)):
        rows = (t >= a) & (t <= b)
        assert rows.sum() > 100 and np.all(log.armed[rows] == armed), (a, b)
    est = flown["estimates"]
    for axis, span in ((0, 0.030), (1, 0.030), (2, 0.040)):  # within 10 % of the range the study draws from
        e = est[f"joint.cog_offset[{axis}]"]
        assert abs(e["value"] - COG[axis]) <= 0.1 * span, (axis, e["value"], COG[axis])


def test_refusals_name_the_reason(rig, client):
    ack = command(client, M.MAV_CMD_HILMS_SYSID, 1)
    assert ack.result == DENIED
    assert recv_text(client, lambda t: "sysid refused: the rig is disarmed: arm it first" in t) is not None
    mode = command(client, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MD.AUTO, MD.AUTO_SYSID)
    assert mode.result == DENIED
    assert recv_text(client, lambda t: "the rig is disarmed" in t) is not None
    for bad, said in ((2, "param1 (2)"), (NAN, "param1 (unset)"), (0.5, "param1 (0.5)")):
        assert command(client, M.MAV_CMD_HILMS_SYSID, bad).result == DENIED
        assert recv_text(client, lambda t: t.startswith("sysid rejected: " + said) and "must be 1" in t) is not None
    assert command(client, M.MAV_CMD_HILMS_SYSID, 0).result == ACCEPTED  # nothing to abort
    # as a mission item: param1 must be 1, and nothing may follow it
    mc = MissionClient(client)
    item = MissionItem(seq=0, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_HILMS_SYSID, param1=0.0)
    assert mc.upload([item]) == M.MAV_MISSION_INVALID_PARAM1
    assert recv_text(client, lambda t: "item 0: MAV_CMD_HILMS_SYSID param1 0 must be 1" in t) is not None
    delay = MissionItem(seq=1, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_NAV_DELAY, param1=1.0)
    assert mc.upload([MissionItem(seq=0, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_HILMS_SYSID, param1=1.0),
                      delay]) == M.MAV_MISSION_INVALID
    assert recv_text(client, lambda t: "item 1: nothing may follow item 0 MAV_CMD_HILMS_SYSID" in t) is not None


def _mode_beat(conn, mode, timeout=10.0):
    return recv(conn, "HEARTBEAT", timeout, lambda m: m.get_srcSystem() == 1 and m.custom_mode == mode)


def _command_texts(conn, cmd, *params, timeout=10.0):
    """COMMAND_LONG -> (its ACK's result, the STATUSTEXTs around it): a stop is said while the command acts,
    before its ACK; a refusal's reason follows the ACK (both in the same flush of the rig's loop)."""
    p = list(params) + [NAN] * (7 - len(params))
    conn.mav.command_long_send(1, 1, cmd, 0, *p)
    texts, parts, result, deadline = [], {}, None, time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = recv(conn, ["COMMAND_ACK", "STATUSTEXT", "HEARTBEAT"], max(deadline - time.monotonic(), 0.01))
        if m is None or (m.get_type() == "HEARTBEAT" and result is not None):
            break  # (the HEARTBEAT after a mode change follows the ACK and its texts)
        if m.get_type() == "STATUSTEXT":  # MAVLink 2 chunks of one text share an id
            text = _text(m)
            if m.id:
                parts.setdefault(m.id, []).append(text)
                if len(text) == 50:
                    continue
                text = "".join(parts.pop(m.id))
            texts.append(text)
        elif m.get_type() == "COMMAND_ACK" and m.command == cmd:
            result = m.result
            deadline = min(deadline, time.monotonic() + 1.0)  # a bound for the texts that follow, not a measure
    return result, texts


def _stopped(texts, why):
    return any(t.startswith("sysid: stopped at ") and t.endswith(why) for t in texts)


def test_a_mode_change_an_abort_and_a_disarm_stop_it(rig, client):
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    assert command(client, M.MAV_CMD_HILMS_SYSID, 1).result == ACCEPTED
    assert _mode_beat(client, SYSID_MODE).base_mode & ARMED
    assert recv_text(client, lambda t: t == "sysid: settle (0-3 s)") is not None
    assert command(client, M.MAV_CMD_HILMS_SYSID, 1).result == DENIED
    assert recv_text(client, lambda t: "sysid refused: already flying" in t and "param1 = 0 aborts" in t) is not None

    result, texts = _command_texts(client, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MD.POSCTL)
    assert result == ACCEPTED and _stopped(texts, ": mode POSCTL"), texts
    assert _mode_beat(client, MD.custom_mode(MD.POSCTL, 0)).base_mode & ARMED

    # entered as a mode (DO_SET_MODE), aborted with param1 = 0: the rig holds, armed
    result, texts = _command_texts(client, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MD.AUTO,
                                   MD.AUTO_SYSID)
    assert result == ACCEPTED and f"sysid: identification flight started ({DURATION_S:g} s)" in texts, texts
    result, texts = _command_texts(client, M.MAV_CMD_HILMS_SYSID, 0)
    assert result == ACCEPTED and _stopped(texts, ": aborted by command"), texts
    assert _mode_beat(client, LOITER).base_mode & ARMED

    assert command(client, M.MAV_CMD_HILMS_SYSID, 1).result == ACCEPTED
    result, texts = _command_texts(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 0)
    assert result == ACCEPTED and _stopped(texts, ": disarmed by command"), texts
    assert not _mode_beat(client, LOITER).base_mode & ARMED


def test_the_mission_reaches_the_item_and_flies_the_programme(rig, client):
    items = [MissionItem(seq=0, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_NAV_DELAY, param1=1.0, current=1),
             MissionItem(seq=1, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_HILMS_SYSID, param1=1.0)]
    assert MissionClient(client).upload(items) == M.MAV_MISSION_ACCEPTED
    assert command(client, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    assert command(client, M.MAV_CMD_MISSION_START, 0, 0).result == ACCEPTED
    # the delay (held 1 s where the rig is), then the item: the programme starts in AUTO.MISSION
    assert recv_text(client, lambda t: t == f"sysid: identification flight started by mission item 1 ({DURATION_S:g} s)") is not None
    cur = recv(client, "MISSION_CURRENT", 10, lambda m: m.seq == 1)
    assert cur.mission_state == M.MISSION_STATE_ACTIVE
    assert recv_text(client, lambda t: t == "sysid: roll chirp (3-17 s)", timeout=20) is not None
    assert _mode_beat(client, MD.custom_mode(MD.AUTO, MD.AUTO_MISSION)).base_mode & ARMED
    # leaving the mission's mode stops the programme and pauses the mission at the item
    result, texts = _command_texts(client, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MD.AUTO,
                                   MD.AUTO_LOITER)
    assert result == ACCEPTED and _stopped(texts, ": mode AUTO.LOITER"), texts
    paused = recv(client, "MISSION_CURRENT", 10, lambda m: m.mission_state == M.MISSION_STATE_PAUSED)
    assert paused.seq == 1


def _ack(server, channel, sent, cmd, *params):
    """COMMAND_LONG ``cmd`` handed to ``server`` from ``channel``: (its COMMAND_ACK's result, the STATUSTEXTs
    that came with it, chunks joined)."""
    sent.clear()
    p = list(params) + [0.0] * (7 - len(params))
    server.handle(M.MAVLink_command_long_message(server.sysid, 1, cmd, 0, *p), channel)
    texts = "".join(_text(m) for m in sent if m.get_type() == "STATUSTEXT")
    return next(m.result for m in sent if m.get_type() == "COMMAND_ACK"), texts


def test_commands_that_need_the_rig_still_are_refused_during_a_disarmed_swing():
    """Chunk by chunk (the messages handled as a socket delivers them): in the roll swing the rig is disarmed,
    yet a reboot, a motor test or a calibration is refused while the programme runs; a disarm command stops it."""
    server = RigServer(prepare_rig(load_config()), [], speedup=1.0)
    try:
        channel, sent = capture_channel(server)

        def ack(cmd, *params):
            return _ack(server, channel, sent, cmd, *params)

        for _ in range(20):
            server.step_chunk()
        assert ack(M.MAV_CMD_COMPONENT_ARM_DISARM, 1)[0] == ACCEPTED
        assert ack(M.MAV_CMD_HILMS_SYSID, 1)[0] == ACCEPTED
        swing = next(a for name, a, _ in PARTS if name == "roll swing") + 5.0  # disarmed since 3.5 s into it
        while server.rig.sysid_status().elapsed_s < swing:
            server.step_chunk()
        assert not server.rig.armed and server.sysid_flight.running
        for cmd, params, what in ((M.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, (1,), "reboot"),
                                  (M.MAV_CMD_DO_MOTOR_TEST, (1, 0, 10, 1), "motor test"),
                                  (M.MAV_CMD_PREFLIGHT_CALIBRATION, (1,), "calibration")):
            result, texts = ack(cmd, *params)
            assert result == DENIED and f"{what} refused: the identification flight is running ({swing:.1f} s, " \
                "roll swing)" in texts, (what, texts)
        result, texts = ack(M.MAV_CMD_COMPONENT_ARM_DISARM, 0)
        assert result == ACCEPTED and "disarmed by command" in texts and not server.sysid_flight.running
        assert (server.modes.main, server.modes.sub) == (MD.AUTO, MD.AUTO_LOITER)
        assert ack(M.MAV_CMD_DO_MOTOR_TEST, 2, 0, 10, 1)[0] == ACCEPTED  # the bench is the user's again
        for _ in range(1400):  # 7 s: past the swing's end, where the programme would arm it again: it never does
            server.step_chunk()
        assert not server.rig.armed
    finally:
        server.close()


def test_a_rig_unlike_the_preset_flies_the_whole_programme_inside_the_fence():
    """Served with the default geofence (100 m, 50 m up, action hold), a rig whose motors are 3 % stronger than
    the preset's and whose centre of gravity is 11 mm off axis (it hangs 16 deg tilted: armable) flies the
    programme to its end: the position hold keeps the virtual position inside the fence. Open loop it climbed
    through the 50 m ceiling 25 s in, and the fence's hold stopped the programme. Chunk by chunk, as the test
    above."""
    cfg = load_config(overrides={"motors.thrust_gain": [1.05, 0.95, 1.05, 1.05], "motors.thrust_bias_grf": -14.0,
                                 "joint.cog_offset": [-0.010, -0.005, 0.04]})
    assert cfg["fence.enabled"] and cfg["fence.action"] == "hold"
    server = RigServer(prepare_rig(cfg), [], speedup=1.0)
    try:
        channel, sent = capture_channel(server)
        for _ in range(20):
            server.step_chunk()
        for cmd in (M.MAV_CMD_COMPONENT_ARM_DISARM, M.MAV_CMD_HILMS_SYSID):
            result, texts = _ack(server, channel, sent, cmd, 1)
            assert result == ACCEPTED, texts
        farthest, texts = 0.0, []
        while server.sysid_flight.running:
            server.step_chunk()
            x, y, _ = server.rig.sim.sensing.state.onboard[0:3]
            farthest = max(farthest, math.hypot(x, y))
            texts += [_text(m) for m in sent if m.get_type() == "STATUSTEXT"]
            sent.clear()
        assert f"sysid: done ({DURATION_S:g} s), disarmed" in texts, "\n".join(texts)
        assert not [t for t in texts if "fence" in t or "stopped" in t], texts
        assert farthest < 0.5 * cfg["fence.radius"]
    finally:
        server.close()
