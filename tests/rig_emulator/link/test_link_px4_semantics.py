"""PX4's semantics on the default plant (`hilms`, the hardware rig) over real sockets (pymavlink):
holds made where the vehicle is as its controllers fly it (after a long hover, when the onboard
estimate and the physics have parted by metres), set-points that never change the mode, OFFBOARD
only with a fresh set-point stream, a fence that holds under a set-point stream with a true
FENCE_STATUS, far mission items refused for the fence (not for the Earth's curvature),
refusals on every link, and a ground tool that keeps the rig's ground-station link alive.

Every wait is judged on the rig's own time stamps (simulated time); the wall-clock timeouts
are only guards against a hung rig. A set-point stream also has a wall-clock floor (a client
keeping its stream alive, as MAVSDK does), never a judgement."""

import math
import time

import numpy as np
import pytest
from pymavlink import mavutil

from protocol.dialect import mavlink as M
from protocol.geodesy import local_enu_to_global
from protocol.mission_items import MissionItem
from rig_emulator.guidance.offboard import OFB_POS
from rig_emulator.guidance.runner import OFFBOARD as OFFBOARD_GUIDANCE
from rig_emulator.link.commands import modes as MD
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, recv_text, start_offboard

NAN = math.nan
ACCEPTED, DENIED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED
POS_ONLY = (M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE
            | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE | M.POSITION_TARGET_TYPEMASK_AX_IGNORE
            | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
            | M.POSITION_TARGET_TYPEMASK_YAW_IGNORE | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE)
SPEEDUP = 20.0
HOLD_TOLERANCE_M = 0.5  # a hold starts where the rig is; main's holds from the physics were metres off


def _gcs(rig, sysid=255):
    conn = connect(rig.tcp_url, source_system=sysid)
    conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    assert recv(conn, "ATTITUDE", 600.0) is not None  # the step loop runs (compiled)
    return conn


def _set_mode(conn, name):
    base, main, sub = mavutil.px4_map[name]
    return command(conn, M.MAV_CMD_DO_SET_MODE, base, main, sub)


def _mode(conn):
    hb = recv(conn, "HEARTBEAT", 10.0, lambda m: m.get_srcSystem() == 1)
    return MD.split_custom_mode(hb.custom_mode)


def _wait_sim(conn, seconds, every=None, each=None):
    """Read ATTITUDE until its stamps advanced ``seconds``; ``each()`` every ``every`` s of them."""
    m = recv(conn, "ATTITUDE", 10.0)
    t0 = t_next = m.time_boot_ms * 1e-3
    t = t0
    while t - t0 < seconds:
        if every is not None and t >= t_next:
            each()
            t_next += every
        m = recv(conn, "ATTITUDE", 10.0)
        assert m is not None, "the rig stopped sending ATTITUDE"
        t = m.time_boot_ms * 1e-3
    return t


def _take_off(conn, rig, alt):
    assert command(conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == ACCEPTED
    ack = command(conn, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, NAN, NAN, NAN, rig.server.ctx.home.alt_m + alt)
    assert ack.result == ACCEPTED
    assert recv_text(conn, lambda t: "takeoff complete" in t, timeout=120) is not None


def _target_and_position(conn):
    """The next POSITION_TARGET_LOCAL_NED and the LOCAL_POSITION_NED after it (NED, m)."""
    tgt = recv(conn, "POSITION_TARGET_LOCAL_NED", 10.0)
    pos = recv(conn, "LOCAL_POSITION_NED", 10.0, lambda m: m.time_boot_ms >= tgt.time_boot_ms)
    return np.array([tgt.x, tgt.y, tgt.z]), np.array([pos.x, pos.y, pos.z])


def _assert_held_here(conn, what):
    target, here = _target_and_position(conn)
    gap = float(np.linalg.norm(target - here))
    assert gap < HOLD_TOLERANCE_M, f"{what}: target {target.round(2)} is {gap:.2f} m from the rig at {here.round(2)}"


def _local(conn, n, e, d):
    conn.mav.set_position_target_local_ned_send(0, 1, 1, M.MAV_FRAME_LOCAL_NED, POS_ONLY, n, e, d,
                                                0, 0, 0, 0, 0, 0, 0, 0)


def test_every_hold_after_a_long_hover_starts_where_the_rig_is():
    """After a minute's hover the estimate the controllers fly and the physics are metres apart on
    `hilms`; POSCTL, AUTO.LOITER, the offboard-loss hold, the fence hold, the return's and the
    landing's first set-point must all start at the position the rig reports and flies."""
    with RigThread(speedup=SPEEDUP, overrides={"fence.alt_max": 10.0}) as rig:
        conn = _gcs(rig)
        _take_off(conn, rig, 2.5)
        _wait_sim(conn, 60.0)
        true, est = rig.server.rig.snapshot().true_position, rig.server.rig.position_now()
        print(f"\nafter 60 s: estimate minus physics {np.round(np.subtract(est, true), 2)} m (ENU)")
        assert _set_mode(conn, "POSCTL").result == ACCEPTED
        _assert_held_here(conn, "POSCTL")
        assert _set_mode(conn, "LOITER").result == ACCEPTED
        _assert_held_here(conn, "AUTO.LOITER")
        # offboard: a set-point where the rig is, then silence: the loss (1 s) holds
        _, here = _target_and_position(conn)
        assert start_offboard(conn, lambda: _local(conn, *here)).result == ACCEPTED
        got = recv_text(conn, lambda t: t.startswith("offboard set-points lost"), timeout=30.0)
        assert got is not None and "hold" in got[1], got
        _assert_held_here(conn, "offboard-loss hold")
        # the fence's hold: a ceiling 0.4 m above, a climbing stream
        _, here = _target_and_position(conn)
        conn.mav.param_set_send(1, 1, b"FENCE_ALT_MAX", float(-here[2] + 0.4), M.MAV_PARAM_TYPE_REAL32)
        assert recv(conn, "PARAM_VALUE", 10.0, lambda m: m.param_id == "FENCE_ALT_MAX") is not None
        climb = lambda: _local(conn, here[0], here[1], here[2] - 1.0)  # noqa: E731
        assert start_offboard(conn, climb).result == ACCEPTED
        t_sim = 0.0
        while rig.server.fence.breach_count == 0:  # the rig's own record of the breach
            _wait_sim(conn, 0.1)
            climb()
            t_sim += 0.1
            assert t_sim < 30.0, "no fence breach"
        assert recv(conn, "HEARTBEAT", 10.0, lambda m: MD.split_custom_mode(m.custom_mode) == (MD.AUTO, MD.AUTO_LOITER))
        _assert_held_here(conn, "fence hold")
        conn.mav.param_set_send(1, 1, b"FENCE_ALT_MAX", 10.0, M.MAV_PARAM_TYPE_REAL32)
        assert recv(conn, "PARAM_VALUE", 10.0, lambda m: m.param_id == "FENCE_ALT_MAX") is not None
        _wait_sim(conn, 2.0)
        assert _set_mode(conn, "RTL").result == ACCEPTED
        _assert_held_here(conn, "AUTO.RTL start")
        _wait_sim(conn, 1.0)
        assert _set_mode(conn, "LAND").result == ACCEPTED
        target, here = _target_and_position(conn)
        assert np.linalg.norm(target[:2] - here[:2]) < HOLD_TOLERANCE_M, ("AUTO.LAND", target, here)
        conn.close()


def test_setpoints_never_change_the_mode_and_offboard_needs_a_fresh_stream():
    with RigThread(speedup=SPEEDUP) as rig:
        conn = _gcs(rig)
        other = _gcs(rig, sysid=254)
        assert _mode(conn) == (MD.POSCTL, 0)
        # no stream: refused, with PX4's reason, on every link
        ack = _set_mode(conn, "OFFBOARD")
        assert ack.result == DENIED
        assert recv_text(conn, lambda t: "no offboard signal" in t) is not None
        assert recv_text(other, lambda t: "no offboard signal" in t) is not None
        # a 10 Hz stream in POSCTL is stored, not flown, and never changes the mode
        _wait_sim(conn, 2.0, 0.1, lambda: _local(conn, 1.0, 2.0, -1.5))
        assert _mode(conn) == (MD.POSCTL, 0)
        assert rig.server.rig.sim.gp.gtype != OFFBOARD_GUIDANCE  # stored, not flown
        # the stream stopped 1 s ago: stale, refused
        _wait_sim(conn, 1.0)
        assert _set_mode(conn, "OFFBOARD").result == DENIED
        assert recv_text(conn, lambda t: "no offboard signal (last set-point" in t) is not None
        assert _mode(conn) == (MD.POSCTL, 0)
        # streaming again: the legacy SET_MODE message switches, answered like DO_SET_MODE
        _local(conn, 1.0, 2.0, -1.5)
        conn.mav.set_mode_send(1, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MD.custom_mode(MD.OFFBOARD, 0))
        ack = recv(conn, "COMMAND_ACK", 10.0, lambda m: m.command == M.MAV_CMD_DO_SET_MODE)
        assert ack is not None and ack.result == ACCEPTED
        assert _mode(conn) == (MD.OFFBOARD, 0)
        gp = rig.server.rig.sim.gp  # disarmed, the rig reports no target: read what its guidance flies
        assert gp.gtype == OFFBOARD_GUIDANCE  # the stored set-point is flown: world ENU (east, north, up)
        assert np.allclose(gp.offboard[OFB_POS:OFB_POS + 3], [2.0, 1.0, 1.5], atol=1e-6), gp.offboard
        assert rig.server.offboard.accepted >= 20
        conn.close()
        other.close()


def _fence_status(conn):
    conn.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0, M.MAVLINK_MSG_ID_FENCE_STATUS, 0, 0, 0, 0, 0, 0)
    return recv(conn, "FENCE_STATUS", 10.0)


def _stream_for(conn, seconds, n, e, d):
    """Set-points at 10 Hz of simulated time for ``seconds``, and at least every 20 ms of wall time
    (0.4 s of rig time at 20x): the stamps read are the rig's clock as this client has caught up
    with it, and a client that falls behind a rig in its own process would space its set-points
    past COM_OF_LOSS_T by them alone. Returns the farthest horizontal distance seen."""
    far = 0.0
    m = recv(conn, "LOCAL_POSITION_NED", 10.0)
    t0 = t_next = m.time_boot_ms * 1e-3
    t = t0
    sent = 0.0
    while t - t0 < seconds:
        if t >= t_next or time.monotonic() - sent > 0.02:
            _local(conn, n, e, d)
            sent = time.monotonic()
            if t >= t_next:
                t_next = t + 0.1
        m = recv(conn, "LOCAL_POSITION_NED", 10.0)
        t = m.time_boot_ms * 1e-3
        far = max(far, math.hypot(m.x, m.y))
    return far, math.hypot(m.x, m.y)


def test_fence_holds_under_a_setpoint_stream_and_fence_status_is_true():
    with RigThread(speedup=SPEEDUP, overrides={"fence.radius": 8.0, "fence.action": "hold"}) as rig:
        conn = _gcs(rig)
        watch = _gcs(rig, sysid=254)  # a second ground station that only reads the rig's STATUSTEXT
        watch.mav.request_data_stream_send(1, 1, M.MAV_DATA_STREAM_ALL, 0, 0)  # no telemetry to pile up unread
        _take_off(conn, rig, 2.5)
        assert start_offboard(conn, lambda: _local(conn, 20.0, 0.0, -2.5)).result == ACCEPTED
        far, now = _stream_for(conn, 25.0, 20.0, 0.0, -2.5)
        print(f"\n25 s of 10 Hz set-points to N 20 m with an 8 m fence: farthest {far:.2f} m, now {now:.2f} m")
        assert far < 10.0 and now < 9.0, (far, now)  # held near the breach, not at 20 m
        assert _mode(conn) == (MD.AUTO, MD.AUTO_LOITER)
        fs = _fence_status(conn)
        assert (fs.breach_status, fs.breach_count, fs.breach_type) == (1, 1, M.FENCE_BREACH_BOUNDARY)
        # the operator takes over (a mode command) and brings it back inside
        assert start_offboard(conn, lambda: _local(conn, 0.0, 0.0, -2.5)).result == ACCEPTED
        for _ in range(30):
            _, now = _stream_for(conn, 1.0, 0.0, 0.0, -2.5)
            if now < 6.0:
                break
        assert now < 6.0, now
        got = recv_text(watch, lambda t: t.startswith("fence"), timeout=10.0)  # the texts in order
        assert got is not None and got[1].startswith("fence breach"), got
        assert recv_text(watch, lambda t: t.startswith("fence"), timeout=10.0)[1] == "fence: back inside"
        fs = _fence_status(conn)
        assert (fs.breach_status, fs.breach_count) == (0, 1)
        # out again: a second breach, counted, held again. OFFBOARD asked for again: the pauses of the
        # stream above (reading the texts and FENCE_STATUS) may outlast COM_OF_LOSS_T (1 s of rig time,
        # 50 ms of wall time at 20x) on a busy machine, and then the offboard-loss hold has taken over
        assert start_offboard(conn, lambda: _local(conn, 20.0, 0.0, -2.5)).result == ACCEPTED
        far, now = _stream_for(conn, 25.0, 20.0, 0.0, -2.5)
        assert far < 10.0 and now < 9.0, (far, now)
        fs = _fence_status(conn)
        assert (fs.breach_status, fs.breach_count) == (1, 2)
        assert _mode(conn) == (MD.AUTO, MD.AUTO_LOITER)
        conn.close()
        watch.close()


def _far_item(home, east, north, frame=M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, z=2.0):
    lat, lon, _ = local_enu_to_global(home, [east, north, 0.0])
    return MissionItem(seq=0, frame=frame, command=M.MAV_CMD_NAV_WAYPOINT, current=1, x=round(lat * 1e7) / 1e7,
                       y=round(lon * 1e7) / 1e7, z=z)


def test_far_items_are_refused_for_the_fence_and_refusals_reach_every_link():
    with RigThread(speedup=SPEEDUP) as rig:
        conn = _gcs(rig)
        other = _gcs(rig, sysid=254)
        home = rig.server.ctx.home
        assert MissionClient(conn).upload([_far_item(home, 0.0, 50_000.0)]) == M.MAV_MISSION_INVALID_PARAM5_X
        got = recv_text(other, lambda t: t.startswith("mission upload failed"))
        assert got is not None and "outside the fence radius" in got[1] and "FENCE_RADIUS" in got[1], got
        assert "under the ground" not in got[1]
        assert MissionClient(conn).upload([_far_item(home, 50_000.0, 0.0)]) == M.MAV_MISSION_INVALID_PARAM6_Y
        # AMSL frame: 2 m above home's altitude is 2 m up, however far
        item = _far_item(home, 0.0, 50_000.0, M.MAV_FRAME_GLOBAL_INT, home.alt_m + 2.0)
        assert MissionClient(conn).upload([item]) == M.MAV_MISSION_INVALID_PARAM5_X
        assert command(conn, M.MAV_CMD_DO_FENCE_ENABLE, 0).result == ACCEPTED
        # fence off: the leg limit (MIS_DIST_WPS) still refuses it, naming the leg, not the ground
        assert MissionClient(conn).upload([_far_item(home, 0.0, 50_000.0)]) == M.MAV_MISSION_INVALID_PARAM5_X
        got = recv_text(other, lambda t: t.startswith("mission upload failed") and "MIS_DIST_WPS" in t)
        assert got is not None and "50.00 km leg from home" in got[1], got
        # a refused mode: the ACK to the asker only, the reason to both
        assert _set_mode(conn, "MANUAL").result == DENIED
        assert recv_text(other, lambda t: "MANUAL needs stick input" in t) is not None
        assert recv(other, "COMMAND_ACK", 1.0) is None
        conn.close()
        other.close()


def test_rig_gcs_fly_sends_heartbeats_and_the_rig_never_loses_its_ground_station(monkeypatch, capsys):
    """`rig-gcs fly` keeps the ground-station link alive: its HEARTBEAT period and the rig's
    GCS-loss timeout are both judged on the rig's simulated clock here, so
    the test is about the tool sending at all, at 1 Hz, not about the host's speed."""
    import gcs_tools.link
    from gcs_tools.cli import main
    from rig_emulator.testing.rig import client_url

    # The tool and the rig share this process: the rig's clock runs on while the host stalls the
    # tool, so the rig runs at 4x (a 10 s GCS timeout is then 2.5 s of wall time without a beat)
    with RigThread(speedup=4.0, overrides={"failsafe.gcs_timeout": 10.0}) as rig:
        srv = rig.server
        clock = lambda: srv.rig.time_s  # noqa: E731
        monkeypatch.setattr(gcs_tools.link, "heartbeat_clock", clock)
        srv.gcs_loss.clock = clock
        texts = []
        statustext = srv.statustext
        monkeypatch.setattr(srv, "statustext", lambda ch, sev, text: (texts.append(text), statustext(ch, sev, text)))
        heard = []
        heartbeat_in = srv.gcs_loss.heard
        monkeypatch.setattr(srv.gcs_loss, "heard", lambda msg: (
            msg.type == M.MAV_TYPE_GCS and heard.append(clock()), heartbeat_in(msg))[1])
        assert main(["fly", client_url(rig.tcp_url), "--rectangle", "2x1", "--altitude", "1", "--timeout", "120"]) == 0, (
            texts, capsys.readouterr())
        t_end = srv.rig.time_s
        out = capsys.readouterr().out
        assert "all 5 waypoints reached" in out, out
        assert not any("ground station lost" in t for t in texts), texts
        assert t_end > 10.0 and len(heard) >= 0.7 * (t_end - heard[0]), (t_end, heard[:3], len(heard))  # ~1 Hz
        gaps = np.diff(heard)
        assert gaps.max() < 10.0, gaps.max()


def test_link_heartbeat_is_sent_once_a_period():
    import gcs_tools.link as L

    class Fake:
        sent = 0

        def heartbeat_send(self, *args):
            Fake.sent += 1

    now = [0.0]
    link = object.__new__(L.Link)
    link.url, link.heartbeats_sent, link._next_heartbeat = "fake", 0, -math.inf
    link.conn = type("C", (), {"mav": Fake()})()
    original = L.heartbeat_clock
    L.heartbeat_clock = lambda: now[0]
    try:
        for t in np.arange(0.0, 5.0, 0.05):
            now[0] = float(t)
            link.heartbeat_if_due()
    finally:
        L.heartbeat_clock = original
    assert link.heartbeats_sent == Fake.sent == 5  # t = 0, 1, 2, 3, 4


@pytest.mark.parametrize("north, east, field", [(50_000.0, 0.0, "x"), (0.0, 50_000.0, "y")])
def test_surface_distance_of_a_far_point(north, east, field):
    """The fence's distance of a global item is along the ellipsoid: the tangent plane's
    horizontal projection at 50 km is 0.5 m shorter and its up is 196 m under the ground."""
    from protocol.geodesy import Home, global_to_local_enu, surface_offset

    home = Home(35.7, 51.4, 1200.0)
    lat, lon, _ = local_enu_to_global(home, [east, north, 0.0])
    enu = global_to_local_enu(home, lat, lon, home.alt_m)
    d, e, n = surface_offset(home, lat, lon)
    assert enu[2] < -190.0  # the tangent plane reads the curvature as depth
    assert d > math.hypot(enu[0], enu[1]) + 0.3 and abs(d - 50_000.0) < 60.0
    assert (abs(n) > abs(e)) == (field == "x")
