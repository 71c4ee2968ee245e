"""The rig as ArduPilot SITL's physics over its JSON interface, flown by the stand-in ArduPilot
(gcs_tools/ardupilot_peer.py: SIM_JSON's packets, parser and clock) over real UDP sockets on
127.0.0.1, on the default (``hilms``) plant: lockstep on the frame counter, repeated frames,
the timestamp clock, sessions, bad packets, the ground link beside it."""

from __future__ import annotations

import math
import socket
import struct
import threading

from gcs_tools.ardupilot_peer import MAGIC_16, HoverController, JsonLink, fly, parse_sensors
from protocol.geodesy import Home
from rig_emulator.config.loader import load_config
from rig_emulator.link.ardupilot_json.server import JsonPhysicsServer
from rig_emulator.link.server import RigServer
from rig_emulator.link.serve import prepare_rig
from rig_emulator.simulation.lockstep import LockstepPlant
from rig_emulator.testing.rig import connect, recv

HOME = Home(35.7, 51.4, 1200.0)
ANSWER_TIMEOUT_S = 120.0  # a bound, not a measure: a cold numba cache compiles at the first session


class JsonRig:
    """A served rig in --ardupilot-json mode in a thread of the test process."""

    def __init__(self, ground: bool = False, airframe: str = "hilms", rate_hz: float = 1000.0):
        cfg = load_config(airframe=airframe, scenario="hover")
        self.rig = prepare_rig(cfg)
        self.ground = RigServer(self.rig, ["tcpin:127.0.0.1:0"] if ground else [], home=HOME, speedup=0.0)
        self.lines: list[str] = []
        self.plant = LockstepPlant(self.rig, rate_hz, HOME.alt_m)
        self.plant.restart()  # compiles (cold cache) before any peer waits on it
        self.server = JsonPhysicsServer(self.ground, "127.0.0.1", 0, self.plant, log=self.lines.append)
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    @property
    def port(self) -> int:
        return self.server.sock.getsockname()[1]

    def link(self, **kw) -> JsonLink:
        return JsonLink("127.0.0.1", self.port, timeout_s=ANSWER_TIMEOUT_S, **kw)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.server.stop()
        self.thread.join(10)
        self.server.close()
        self.ground.close()


def _tilt_deg(state) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(state[1]) * math.cos(state[2])))))


def test_hover_in_lockstep_on_the_hardware_rig_and_two_sessions_identical():
    """The hardware rig hangs at about 13 deg when disarmed; the stand-in levels it and holds 1 m.
    Every frame is one 1 ms step of the physics' clock; a second ArduPilot (a new address, frame 0)
    gets a fresh plant: the same run, byte for byte."""
    with JsonRig() as rig:
        runs = []
        for _ in range(2):
            link = rig.link()
            link.record = True
            log = fly(link, 10.0, HoverController(altitude_m=1.0))
            link.close()
            runs.append((log, link))
        (a, la), (b, lb) = runs
        # the clock: 1 ms a frame from the first, every frame moved SITL's clock, no reset within a session
        times = [s[0] for s in a.states]
        assert times[0] == 0.001 and all(abs((t1 - t0) - 0.001) < 1e-9 for t0, t1 in zip(times, times[1:]))
        assert la.clock.advances == a.frames and la.clock.resets == 0
        assert la.clock.time_now_us == __import__("pytest").approx(times[-1] * 1e6)
        # the flight
        assert max(_tilt_deg(s) for s in a.states if 0.45 <= s[0] <= 0.5) > 10.0  # hanging when it arms
        assert all(_tilt_deg(s) < 4.0 for s in a.states if s[0] >= 4.0)
        held = [s[4] for s in a.states if s[0] >= 6.0]
        assert held and all(abs(h - 1.0) < 0.15 for h in held), held[:: max(1, len(held) // 10)]
        # a new session restarts the plant: the same answers, byte for byte
        assert la.lines == lb.lines and len(la.lines) == a.frames
        assert rig.server.sessions == 2 and rig.plant.rig.sim.k == b.frames  # one physics step per frame
        assert sum("the plant starts afresh" in line for line in rig.lines) == 2


def test_repeated_frames_are_answered_without_stepping():
    with JsonRig() as rig:
        link = rig.link()
        link.send([1000] * 4)
        first, v1 = link.receive()
        link.frame_count -= 1  # SITL re-sends the frame it got no answer to: the same frame_count
        link.resend()
        again, v2 = link.receive()
        assert again == first and v2["timestamp"] == v1["timestamp"] == 0.001
        assert link.clock.advances == 1  # SITL's clock did not move on the repeat
        link.send([1500] * 4)
        _, v3 = link.receive()
        assert v3["timestamp"] == 0.002
        s = rig.server.session
        assert (s.steps, s.repeats, s.missed) == (2, 1, 0)
        # a lost packet (frame numbers skipped): still one step, the gap counted
        link.frame_count += 3
        link.send([1500] * 4)
        _, v4 = link.receive()
        assert v4["timestamp"] == 0.003 and (s.steps, s.missed) == (3, 3)
        link.close()


def test_thirty_two_channels_and_the_motor_outputs():
    """SERVO_32_ENABLE: 32 channels, magic 29569. SERVO1..4 drive motors 1..4 (1000-2000 us = 0-15 V)."""
    with JsonRig() as rig:
        link = rig.link(channels=32)
        link.send([1000, 1500, 2000, 1250])
        link.receive()
        v = rig.plant.rig.sim.v_cmd
        assert list(v) == [0.0, 7.5, 15.0, 3.75] and rig.plant.rig.sim.armed
        link.send([1000] * 4)  # ArduCopter disarmed: every motor at the minimum
        link.receive()
        assert not rig.plant.rig.sim.armed
        link.close()


def test_bad_packets_are_counted_and_the_rig_keeps_answering():
    with JsonRig() as rig:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.settimeout(ANSWER_TIMEOUT_S)
        try:
            for data in (b"hello", struct.pack("<HHI16H", 4321, 1200, 0, *[1000] * 16),
                         struct.pack("<HHI16H", MAGIC_16, 1200, 0, *[1000] * 16)[:-1]):
                sock.sendto(data, ("127.0.0.1", rig.port))
            link = rig.link()  # a real ArduPilot behind them is served
            log = fly(link, 0.2)
            link.close()
            assert log.frames == 201  # 0.001 .. 0.201 s
            assert rig.server.bad_packets == 3 and rig.ground.counters.dropped["bad_data"] == 3
            assert rig.server.sessions == 1
            assert any("not a servo packet" in line and "magic" not in line for line in rig.lines)
        finally:
            sock.close()


def test_one_ardupilot_at_a_time():
    with JsonRig() as rig:
        first = rig.link()
        fly(first, 0.1)
        # another ArduPilot mid-flight (frame 5, not a fresh start): refused, not answered
        other = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        other.bind(("127.0.0.1", 0))
        other.sendto(struct.pack("<HHI16H", MAGIC_16, 1200, 5, *[1500] * 16), ("127.0.0.1", rig.port))
        fly(first, 0.1)  # the first carries on, its session intact (packets are handled in order)
        assert rig.server.refused == 1 and rig.server.sessions == 1
        assert rig.server.session.addr == first.sock.getsockname()
        # an ArduPilot that has just started (frame 0) takes over: a fresh plant, the clock back to 0
        first.frame_count = 0
        fly(first, 0.05)
        assert first.clock.resets == 1 and rig.server.sessions == 2
        other.close()
        first.close()


def test_ground_link_serves_beside_ardupilot():
    with JsonRig(ground=True) as rig:
        gcs = connect(rig.ground.urls[0])
        try:
            assert recv(gcs, "HEARTBEAT", timeout=30) is not None
            link = rig.link()
            done = {}
            t = threading.Thread(target=lambda: done.setdefault("log", fly(link, 4.0)))
            t.start()
            cells = recv(gcs, "HILMS_LOAD_CELLS", timeout=60, condition=lambda m: max(m.thrust_n) > 3.0)
            servo = recv(gcs, "SERVO_OUTPUT_RAW", timeout=60, condition=lambda m: m.servo1_raw > 1500)
            sim = recv(gcs, "SIM_STATE", timeout=60)
            t.join(120)
            link.close()
            assert cells is not None, "the load cells see ArduPilot's thrust"
            assert servo is not None, "SERVO_OUTPUT_RAW shows ArduPilot's motor commands"
            assert sim is not None
            assert done["log"].frames >= 4000
            assert "tx_overflow" not in rig.ground.counters.dropped
        finally:
            gcs.close()
