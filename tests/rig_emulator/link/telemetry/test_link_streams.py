"""Telemetry streams at their configured rates, counted against their own simulated-time stamps."""

import math
import time

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry.stream_table import STREAMS
from rig_emulator.testing.rig import collect, command, count_in_window, recv, stamp_s

PER_TICK = {"HILMS_IMU_MODULE": 5, "NAMED_VALUE_FLOAT": 4}


def _window(msgs):
    """A window inside the collected span, away from its edges."""
    stamps = sorted(stamp_s(m) for m in msgs)
    return stamps[0] + 0.5, stamps[-1] - 0.5


def test_default_streams_at_their_rates(client):
    got = collect(client, sim_seconds=10.0)
    t0, t1 = _window(got["ATTITUDE"])
    span = t1 - t0
    for stream in STREAMS.values():
        msgs = [m for m in got[stream.name] if stamp_s(m) is not None]
        if not msgs:  # messages without a stamp (VFR_HUD, EXTENDED_SYS_STATE): count over the whole run
            assert got[stream.name], stream.name
            continue
        expected = stream.default_hz * span * PER_TICK.get(stream.name, 1)
        n = count_in_window(msgs, t0, t1)
        assert abs(n - expected) <= 1 + PER_TICK.get(stream.name, 1) + 0.02 * expected, (stream.name, n, expected)


def test_heartbeat_is_one_hertz_of_wall_time(client):
    """At 4x speed-up still one HEARTBEAT per wall-clock second (it carries no stamp): the gaps
    between arrivals, measured here, not the simulated time they span (which shrinks when a
    busy machine slows the rig down)."""
    arrivals = []
    deadline = time.monotonic() + 30.0
    while len(arrivals) < 6 and time.monotonic() < deadline:
        hb = recv(client, "HEARTBEAT", timeout=5.0)
        if hb is not None:
            arrivals.append(time.monotonic())
            last = hb
    gaps = sorted(b - a for a, b in zip(arrivals, arrivals[1:]))
    assert len(gaps) == 5 and 0.75 <= gaps[2] <= 1.3, gaps  # the median gap
    hb = last
    assert (hb.type, hb.autopilot) == (M.MAV_TYPE_QUADROTOR, M.MAV_AUTOPILOT_PX4)
    assert hb.get_srcSystem() == 1 and hb.get_srcComponent() == M.MAV_COMP_ID_AUTOPILOT1
    assert hb.base_mode & M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and not hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED
    assert hb.custom_mode == 3 << 16  # PX4 POSCTL: holding the initial position


def test_set_message_interval_changes_one_stream(client):
    ack = command(client, M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE, 20000)
    assert ack.result == M.MAV_RESULT_ACCEPTED
    assert command(client, M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_SCALED_IMU, -1).result == M.MAV_RESULT_ACCEPTED
    ack = command(client, M.MAV_CMD_GET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE)
    assert ack.result == M.MAV_RESULT_ACCEPTED
    reply = recv(client, "MESSAGE_INTERVAL", condition=lambda m: m.message_id == M.MAVLINK_MSG_ID_ATTITUDE)
    assert reply.interval_us == 20000
    recv(client, "ATTITUDE")  # let messages sent before the change drain
    got = collect(client, sim_seconds=6.0)
    t0, t1 = _window(got["ATTITUDE"])
    n = count_in_window(got["ATTITUDE"], t0, t1)
    assert abs(n - 50 * (t1 - t0)) <= 2, n
    late = [m for m in got["SCALED_IMU"] if stamp_s(m) > t0]
    assert late == []
    assert command(client, M.MAV_CMD_SET_MESSAGE_INTERVAL, 999, 1000).result == M.MAV_RESULT_UNSUPPORTED


def test_legacy_request_data_stream(client):
    client.mav.request_data_stream_send(1, 1, M.MAV_DATA_STREAM_POSITION, 2, 1)
    client.mav.request_data_stream_send(1, 1, M.MAV_DATA_STREAM_RAW_SENSORS, 0, 0)
    first = recv(client, "LOCAL_POSITION_NED")
    got = collect(client, sim_seconds=8.0)
    t0, t1 = _window(got["ATTITUDE"])
    t0 = max(t0, stamp_s(first) + 1.0)
    n = count_in_window(got["LOCAL_POSITION_NED"], t0, t1)
    assert abs(n - 2 * (t1 - t0)) <= 1.5, n
    assert [m for m in got["HIGHRES_IMU"] if stamp_s(m) > t0] == []


def test_telemetry_values_are_consistent(client):
    """At rest on the virtual ground: the accelerometers read gravity's reaction, 1 g along the
    body's up seen at the attitude ATTITUDE reports (the hardware rig hangs about 13-18 deg off
    level from its joint; FRD: z = -g cos(roll) cos(pitch), x = g sin(pitch)), position at the origin.

    The readings are the simulated sensors' (calibrated): one accelerometer sample carries
    about 9 mg of white noise (400 ug/sqrt(Hz) at 500 Hz bandwidth), so samples are averaged.
    """
    att = recv(client, "ATTITUDE")
    imus = [recv(client, "SCALED_IMU") for _ in range(20)]
    zacc = sum(m.zacc for m in imus) / len(imus)
    xacc = sum(m.xacc for m in imus) / len(imus)
    level = math.cos(att.roll) * math.cos(att.pitch)
    assert abs(zacc + 1000 * level) < 10 and abs(xacc - 1000 * math.sin(att.pitch)) < 10, (zacc, xacc, att)
    his = [recv(client, "HIGHRES_IMU") for _ in range(10)]
    assert abs(sum(h.zacc for h in his) / len(his) + 9.81 * level) < 0.05
    gpi = recv(client, "GLOBAL_POSITION_INT")
    home = recv(client, "HOME_POSITION")
    assert abs(gpi.lat - home.latitude) < 10 and abs(gpi.lon - home.longitude) < 10
    gps = recv(client, "GPS_RAW_INT")
    assert gps.fix_type == M.GPS_FIX_TYPE_3D_FIX
    st = recv(client, "SYS_STATUS")
    need = (M.MAV_SYS_STATUS_SENSOR_3D_GYRO | M.MAV_SYS_STATUS_SENSOR_3D_ACCEL | M.MAV_SYS_STATUS_SENSOR_3D_MAG
            | M.MAV_SYS_STATUS_SENSOR_GPS | M.MAV_SYS_STATUS_PREARM_CHECK)
    assert st.onboard_control_sensors_present & need == need
    assert st.onboard_control_sensors_health & need == need
    cells = recv(client, "HILMS_LOAD_CELLS")
    assert cells.health == 0b1111
    mods = {recv(client, "HILMS_IMU_MODULE").module_index for _ in range(10)}
    assert mods == {0, 1, 2, 3, 4}
    names = {recv(client, "NAMED_VALUE_FLOAT").name for _ in range(8)}
    assert names == {"LC1_N", "LC2_N", "LC3_N", "LC4_N"}
