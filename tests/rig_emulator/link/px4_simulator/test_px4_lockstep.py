"""The rig as PX4's simulator, flown by the pymavlink stand-in flight stack
(gcs_tools/px4_peer.py, written from PX4's published protocol): lockstep, hover, identical
sessions, dropped connections, the serial line, the ground link beside it."""

from __future__ import annotations

import math
import os
import socket
import threading
import time

import pytest

from gcs_tools.px4_peer import HoverController, StreamLink, fly
from protocol.geodesy import Home
from rig_emulator.config.loader import load_config
from rig_emulator.link.px4_simulator.server import Px4SimulatorServer
from rig_emulator.link.px4_simulator.transport import open_transport
from rig_emulator.link.server import RigServer
from rig_emulator.link.serve import prepare_rig
from rig_emulator.testing.rig import connect, recv
from rig_emulator.simulation.lockstep import LockstepPlant

HOME = Home(35.7, 51.4, 1200.0)
#: free run before lockstep at 1/100 of real time: one sensor step every 0.4 s of wall time
#: until the peer's first answer, so that its first answer always comes after the first step
FREE_RUN_SPEEDUP = 0.01


class Px4Rig:
    """A served rig in px4-simulator mode in a thread of the test process."""

    def __init__(self, spec: str = "127.0.0.1:0", ground: bool = False, airframe: str = "hilms-ideal",
                 speedup: float = FREE_RUN_SPEEDUP):
        cfg = load_config(airframe=airframe, scenario="hover")
        self.rig = prepare_rig(cfg)
        self.ground = RigServer(self.rig, ["tcpin:127.0.0.1:0"] if ground else [], home=HOME, speedup=0.0)
        self.transport = open_transport(spec)
        self.lines: list[str] = []
        self.plant = LockstepPlant(self.rig, 250.0, HOME.alt_m)
        self.plant.restart()  # compiles (cold cache) before any peer waits on it
        self.server = Px4SimulatorServer(self.ground, self.transport, self.plant, HOME, speedup=speedup,
                                         log=self.lines.append)
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    @property
    def port(self) -> int:
        return int(self.transport.url.rsplit(":", 1)[1])

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.server.stop()
        self.thread.join(10)
        self.server.close()
        self.ground.close()

    def wait_sessions_ended(self, n: int, timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if len(self.server.session_steps) >= n:
                return True
            time.sleep(0.01)
        return False


class RecordingLink(StreamLink):
    """The stand-in's link, keeping every message it received as bytes."""

    received: list

    def messages(self):
        self.received = []
        for msg in super().messages():
            self.received.append(bytes(msg.get_msgbuf()))
            yield msg


def _altitudes(log) -> list[tuple[float, float]]:
    """(t s, altitude above the start m) of the ground truth."""
    alt0 = log.truth[0][5]
    return [(row[0] * 1e-6, (row[5] - alt0) * 1e-3) for row in log.truth]


def _tilt_deg(row) -> float:
    w, x, y, z = row[1:5]
    # angle between body z and NED down: cos = 1 - 2 (x^2 + y^2)
    return math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y)))))


def test_hover_in_lockstep_and_two_sessions_identical():
    with Px4Rig() as rig:
        logs = []
        for _ in range(2):
            link = StreamLink.tcp("127.0.0.1", rig.port)
            logs.append(fly(link, 6.0, HoverController(altitude_m=1.0)))
            link.close()
            assert rig.wait_sessions_ended(len(logs))
        a, b = logs
        # the protocol: strictly 4 ms steps from the first, GPS at 10 Hz, truth at the 5 ms asked for
        times = [s[0] for s in a.sensors]
        assert times[0] == 4000 and all(t1 - t0 == 4000 for t0, t1 in zip(times, times[1:]))
        assert a.gps == pytest.approx(len(times) / 25, abs=1)
        assert len(a.truth) == pytest.approx(len(times) * 4 / 5, abs=2)
        # mag sampled at 100 Hz: its bits on 2 steps in 5; accel/gyro/baro every step
        mag_steps = sum(1 for s in a.sensors if s[-1] & 0x1C0 == 0x1C0)
        assert mag_steps == pytest.approx(len(times) * 2 / 5, abs=2)
        assert all(s[-1] & 0x1A3F == 0x1A3F for s in a.sensors)
        # the flight: climbs to 1 m and holds it level
        held = [(t, h) for t, h in _altitudes(a) if t >= 4.0]
        assert held and all(abs(h - 1.0) < 0.15 for _, h in held), held[:: max(1, len(held) // 10)]
        assert all(_tilt_deg(row) < 5.0 for row in a.truth if row[0] >= 2.0e6)
        # a new session restarts the plant: the same run, bit for bit
        assert a.sensors == b.sensors and a.truth == b.truth
        # the peer's last answer stepped the plant once more before it hung up
        assert rig.server.session_steps == [a.steps + 1, b.steps + 1]
        assert any("flight stack gone" in line for line in rig.lines)


def test_two_sessions_at_the_default_speedup_are_identical_from_the_lockstep_start():
    """At the default ``--speedup`` (1: the free run at real time), with the ground link served
    and a ground station reading its streams. The flight stack answers at once (its first
    HIL_ACTUATOR_CONTROLS in the write that connects it), so both sessions start lockstep at
    t = 0 however busy the machine is; from there nothing paced by the wall clock may reach
    the streams: sensors, GPS and ground truth (whose 5 ms schedule is a grid in simulated
    time, not anchored where SET_MESSAGE_INTERVAL happened to arrive) are the same bit for bit."""
    with Px4Rig(ground=True, speedup=1.0) as rig:
        gcs = connect(rig.ground.urls[0])
        stop = threading.Event()
        got = []

        def drain():  # a ground station taking the rig's streams, so the ground link has work between steps
            while not stop.is_set():
                m = gcs.recv_match(blocking=True, timeout=0.1)
                if m is not None:
                    got.append(m.get_type())

        reader = threading.Thread(target=drain, daemon=True)
        reader.start()
        try:
            logs, streams = [], []
            for _ in range(2):
                link = RecordingLink.tcp("127.0.0.1", rig.port)
                logs.append(fly(link, 3.0, HoverController(altitude_m=1.0), answer_at_connect=True))
                link.close()
                assert rig.wait_sessions_ended(len(logs))
                streams.append(link.received)
        finally:
            stop.set()
            reader.join(5)
            gcs.close()
        assert [line for line in rig.lines if "lockstep from" in line] == ["flight stack in lockstep from t = 0.000 s"] * 2
        a, b = logs
        assert a.sensors[0][0] == 4000 and a.steps >= 750 and a.truth
        assert max(row[5] for row in a.truth) - a.truth[0][5] > 500  # it flew (climbed over 0.5 m)
        assert a.sensors == b.sensors and a.truth == b.truth and a.gps == b.gps
        # every message the rig sent, byte for byte (sequence numbers and the COMMAND_ACK included)
        assert len(streams[0]) > 1000 and streams[0] == streams[1]
        assert "HILMS_LOAD_CELLS" in got


def test_the_stand_in_holds_hover_on_the_hardware_rig():
    """The default plant (``hilms``) hangs at about 13 deg roll and pitch when disarmed (its centre of
    gravity off the joint) and needs a steady torque to stay level; its accelerometer, like a
    flying vehicle's, shows thrust rather than tilt. The stand-in's GPS-aided tilt estimate and
    rate integral (as PX4's EKF2 and rate controller) level it and hold 1 m."""
    with Px4Rig(airframe="hilms") as rig:
        link = StreamLink.tcp("127.0.0.1", rig.port)
        log = fly(link, 12.0, HoverController(altitude_m=1.0))
        link.close()
    assert max(_tilt_deg(row) for row in log.truth if 0.4e6 <= row[0] <= 0.5e6) > 10.0  # hanging when armed
    assert all(_tilt_deg(row) < 4.0 for row in log.truth if row[0] >= 4.0e6)
    held = [(t, h) for t, h in _altitudes(log) if t >= 6.0]
    assert held and all(abs(h - 1.0) < 0.15 for _, h in held), held[:: max(1, len(held) // 10)]


def test_dropped_connection_ends_the_session_and_the_rig_waits():
    with Px4Rig() as rig:
        link = StreamLink.tcp("127.0.0.1", rig.port)
        log = fly(link, 1.0)
        link.close()  # mid-flight, motors running
        assert rig.wait_sessions_ended(1)
        assert rig.server.session is None and rig.plant.rig.sim.v_cmd.max() == 0.0
        # a second flight stack while one is served is refused; the first keeps its session
        first = StreamLink.tcp("127.0.0.1", rig.port)
        second = socket.create_connection(("127.0.0.1", rig.port), timeout=5)
        second.settimeout(5)
        assert second.recv(100) == b""  # closed at once
        second.close()
        log2 = fly(first, 0.5)
        first.close()
        assert log2.sensors[0][0] == 4000 and log2.steps >= 125  # a fresh plant
        assert rig.transport.refused == 1
        assert log.steps >= 250


def test_ground_link_serves_beside_the_flight_stack():
    with Px4Rig(ground=True) as rig:
        gcs = connect(rig.ground.urls[0])
        try:
            assert recv(gcs, "HEARTBEAT", timeout=10) is not None
            link = StreamLink.tcp("127.0.0.1", rig.port)
            done = {}
            t = threading.Thread(target=lambda: done.setdefault("log", fly(link, 3.0)))
            t.start()
            cells = recv(gcs, "HILMS_LOAD_CELLS", timeout=20, condition=lambda m: max(m.thrust_n) > 3.0)
            servo = recv(gcs, "SERVO_OUTPUT_RAW", timeout=20, condition=lambda m: m.servo1_raw > 1500)
            t.join(30)
            link.close()
            assert cells is not None, "the load cells see the flight stack's thrust"
            assert servo is not None, "SERVO_OUTPUT_RAW shows the flight stack's motor commands"
            assert done["log"].steps >= 700
        finally:
            gcs.close()


def test_serial_line_pseudo_terminal():
    master, slave = os.openpty()
    path = os.ttyname(slave)
    try:
        with Px4Rig(spec=f"serial:{path}:921600") as rig:
            link = StreamLink.fd(master)
            log = fly(link, 2.0)
            assert log.steps >= 500 and log.sensors[0][0] == 4000
            assert all(t1 - t0 == 4000 for t0, t1 in zip([s[0] for s in log.sensors], [s[0] for s in log.sensors][1:]))
            alt = _altitudes(log)
            assert alt[-1][1] > 0.2  # taking off
    finally:
        os.close(master)
        os.close(slave)


def test_ground_stations_get_full_streams_in_every_session():
    """One rig process, several flight-stack sessions: each session restarts the plant's clock, and
    the ground link's streams (scheduled in simulated time) restart with it. A ground station that
    connected between sessions gets its streams (SIM_STATE among them) in the next one, although that
    session is shorter than the one before; nothing it is sent is dropped."""
    with Px4Rig(ground=True, airframe="hilms") as rig:
        link = StreamLink.tcp("127.0.0.1", rig.port)
        fly(link, 3.0, HoverController(altitude_m=1.0), answer_at_connect=True)
        link.close()
        assert rig.wait_sessions_ended(1)
        gcs = connect(rig.ground.urls[0])
        try:
            assert recv(gcs, "HEARTBEAT", timeout=30) is not None
            link = StreamLink.tcp("127.0.0.1", rig.port)
            done = {}
            t = threading.Thread(target=lambda: done.setdefault(
                "log", fly(link, 1.5, HoverController(altitude_m=1.0), answer_at_connect=True)))
            t.start()
            got = {kind: recv(gcs, kind, timeout=60) for kind in
                   ("SIM_STATE", "ATTITUDE", "HILMS_LOAD_CELLS", "SERVO_OUTPUT_RAW", "GLOBAL_POSITION_INT")}
            t.join(120)
            link.close()
            assert rig.wait_sessions_ended(2)
            assert all(got.values()), [k for k, m in got.items() if m is None]
            assert got["ATTITUDE"].time_boot_ms <= 1504  # from the second session's clock
            assert "tx_overflow" not in rig.ground.counters.dropped, rig.ground.counters.dropped
        finally:
            gcs.close()
