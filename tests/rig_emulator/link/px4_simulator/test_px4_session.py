"""The Simulator MAVLink API session on its own: a stand-in plant (no compiled loop) behind the
real transport and session, a pymavlink peer speaking PX4's side (common dialect)."""

from __future__ import annotations

import socket
import threading
import time

import numpy as np
import pytest
from pymavlink.dialects.v20 import common

from gcs_tools.px4_peer import StreamLink, fly
from protocol.geodesy import Home
from rig_emulator.link.endpoints.counters import LinkCounters
from rig_emulator.link.px4_simulator.server import Px4SimulatorServer
from rig_emulator.link.px4_simulator.transport import open_transport
from rig_emulator.simulation.hil_readout import HilReadout


class StandInPlant:
    """Counts steps and remembers the commands; a vertical point mass for the readout."""

    steps_per_update = 4
    period_s = 0.004
    voltage_max_v = 15.0

    def __init__(self):
        self.restarts = 0
        self.commands = []
        self.k = 0

    def restart(self):
        self.restarts += 1
        self.k, self.z, self.vz, self.v = 0, 0.0, 0.0, [0.0] * 4

    def command(self, voltages, armed):
        self.v = list(voltages)
        self.commands.append((self.k, tuple(voltages), armed))

    @property
    def time_s(self):
        return self.k * 0.001

    def advance(self):
        self.k += 4
        acc = sum(self.v) * 0.467 / 2.23 - 9.81
        if self.z <= 0.0 and acc < 0.0:
            acc, self.vz = 0.0, 0.0
        self.vz += acc * 0.004
        self.z += self.vz * 0.004
        return HilReadout(self.time_s, np.zeros(3), np.array([0.0, 0.0, -9.81 - acc]), np.array([2e-5, 0.0, 3e-5]),
                          True, self.k % 10 < 4, 87000.0 - 11.0 * self.z, 7.0, 1200.0 + self.z,
                          np.array([0.0, 0.0, self.z]), np.array([0.0, 0.0, self.vz]), np.array([0.0, 0.0, acc]),
                          np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3))


class NoGround:
    """A ground link with no endpoints."""

    endpoints = []
    _snap = None

    def __init__(self):
        self.counters = LinkCounters()

    def _heartbeat_if_due(self, now):
        pass

    def service_io(self):
        pass

    def report_faults(self):
        pass

    def emit_streams(self):
        pass

    def flush(self):
        pass

    def clock_restarted(self, t_old):
        pass


@pytest.fixture
def served():
    plant = StandInPlant()
    transport = open_transport("127.0.0.1:0")
    server = Px4SimulatorServer(NoGround(), transport, plant, Home(35.7, 51.4, 1200.0), speedup=1.0, log=lambda _: None)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    yield server, plant, int(transport.url.rsplit(":", 1)[1])
    server.stop()
    thread.join(10)
    server.close()


def _raw(port):
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock, common.MAVLink(None, srcSystem=1, srcComponent=1)


def _read_until(sock, mav, kind, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for m in mav.parse_buffer(sock.recv(4096)) or ():
            if m.get_type() == kind:
                return m
    return None


def test_one_step_per_actuator_message(served):
    server, plant, port = served
    sock, mav = _raw(port)
    first = _read_until(sock, mav, "HIL_SENSOR")  # free run: sensors before any actuator message
    assert first is not None and first.id == 0 and first.time_usec == 4000
    time.sleep(0.1)  # the free run goes on at real time meanwhile
    k_before = plant.k
    assert k_before >= 4
    for i in range(20):
        sock.sendall(common.MAVLink_hil_actuator_controls_message(0, [0.5] * 16, 129, 1).pack(mav))
    deadline = time.monotonic() + 5
    while plant.k < k_before + 80 and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.2)  # lockstep: nothing more moves the plant, however long we wait
    assert plant.k == k_before + 80
    assert plant.commands[-1] == (k_before + 76, (7.5, 7.5, 7.5, 7.5), True)
    sock.close()


def test_message_interval_is_acknowledged_and_obeyed(served):
    server, plant, port = served
    sock, mav = _raw(port)
    sock.sendall(common.MAVLink_command_long_message(0, 0, common.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                                     common.MAVLINK_MSG_ID_HIL_STATE_QUATERNION, 20000, 0, 0, 0, 0,
                                                     0).pack(mav))
    ack = _read_until(sock, mav, "COMMAND_ACK")
    assert ack.command == common.MAV_CMD_SET_MESSAGE_INTERVAL and ack.result == common.MAV_RESULT_ACCEPTED
    got = []
    deadline = time.monotonic() + 10
    while len(got) < 200 and time.monotonic() < deadline:
        got += [m for m in mav.parse_buffer(sock.recv(65536)) or () if m.get_type() in ("HIL_SENSOR", "HIL_STATE_QUATERNION")]
        sock.sendall(common.MAVLink_hil_actuator_controls_message(0, [0.0] * 16, 1, 1).pack(mav))
    sensors = [m for m in got if m.get_type() == "HIL_SENSOR"]
    states = [m for m in got if m.get_type() == "HIL_STATE_QUATERNION"]
    span_s = (sensors[-1].time_usec - sensors[0].time_usec) * 1e-6
    assert len(states) == pytest.approx(span_s / 0.02, abs=2)  # 50 Hz asked, 250 Hz steps
    sock.sendall(common.MAVLink_command_long_message(0, 0, common.MAV_CMD_DO_SET_MODE, 0, 1, 0, 0, 0, 0, 0,
                                                     0).pack(mav))
    nack = _read_until(sock, mav, "COMMAND_ACK")
    assert nack.result == common.MAV_RESULT_UNSUPPORTED
    sock.close()


def test_garbage_does_not_end_the_session(served):
    server, plant, port = served
    link = StreamLink.tcp("127.0.0.1", port)
    link._send(b"\xfd\x09garbage" + bytes(range(256)))
    log = fly(link, 0.5)
    link.close()
    assert log.steps >= 125 and server.sessions == 1


def test_second_flight_stack_is_refused_and_a_reconnect_restarts(served):
    server, plant, port = served
    a = StreamLink.tcp("127.0.0.1", port)
    fly(a, 0.2)
    b = socket.create_connection(("127.0.0.1", port), timeout=5)
    assert b.recv(10) == b""
    b.close()
    a.close()
    c = StreamLink.tcp("127.0.0.1", port)
    log = fly(c, 0.2)
    c.close()
    assert log.first_usec == 4000 and server.transport.refused == 1 and plant.restarts == 2


def test_without_the_lockstep_flag_the_rig_runs_in_real_time(served):
    """A HITL board sends HIL_ACTUATOR_CONTROLS without the lockstep flag: real time."""
    server, plant, port = served
    t_connect = time.monotonic()  # the session (and its plant, from step 0) starts after this
    sock, mav = _raw(port)
    _read_until(sock, mav, "HIL_SENSOR")
    sock.sendall(common.MAVLink_hil_actuator_controls_message(0, [0.2] * 16, 129, 0).pack(mav))
    k0 = plant.k
    time.sleep(0.5)
    k1 = plant.k
    wall_since_connect = time.monotonic() - t_connect
    # steps without messages (at least a few in 0.5 s even on a loaded machine), and never ahead
    # of the wall clock over the whole session: at most the one 4 ms step that starts at once (a
    # loop that fell behind catches up, so the rate over a short window may exceed real time)
    assert (k1 - k0) * 0.001 > 0.02
    assert k1 * 0.001 <= wall_since_connect + 0.004 + 1e-9
    assert plant.v == pytest.approx([3.0] * 4)  # 0.2 as float32, x 15 V
    sock.close()


def test_a_steady_barometer_never_repeats_exactly(served):
    """Seen with PX4 SITL (main, 2025-03): in a steady hover the ideal barometer repeated the
    same pressure, and PX4's DataValidator flags a reading equal (within 1e-6, in Pa as
    float32) to the previous one 100 times in a row as STALE ("BARO #0 failed: STALE!", then
    the second barometer alike). The rig alternates abs_pressure by +-0.01 Pa per step."""
    server, plant, port = served
    sock, mav = _raw(port)
    assert _read_until(sock, mav, "HIL_SENSOR") is not None
    for _ in range(150):  # lockstep on the ground, motors off: the ideal pressure is constant
        sock.sendall(common.MAVLink_hil_actuator_controls_message(0, [0.0] * 16, 1, 1).pack(mav))
    pressures, alts = [], []
    deadline = time.monotonic() + 5
    while len(pressures) < 140 and time.monotonic() < deadline:
        for m in mav.parse_buffer(sock.recv(65536)) or ():
            if m.get_type() == "HIL_SENSOR":
                pressures.append(m.abs_pressure)
                alts.append(m.pressure_alt)
    assert len(pressures) >= 140
    equal_run = longest = 0
    for prev, cur in zip(pressures, pressures[1:]):  # PX4: pressure in Pa (float32), |a - b| < 1e-6
        same = abs(np.float32(np.float32(prev) * np.float32(100.0)) - np.float32(np.float32(cur) * np.float32(100.0))) < 1e-6
        equal_run = equal_run + 1 if same else 0
        longest = max(longest, equal_run)
    assert longest < 100
    assert max(pressures) - min(pressures) < 0.0005  # hPa: +-0.01 Pa about the ideal (about 1 mm)
    assert len(set(alts)) == 1  # pressure_alt stays the ideal altitude
    sock.close()


def test_ground_truth_schedule_is_a_grid_in_simulated_time(served):
    """HIL_STATE_QUATERNION at the 5 ms PX4 asks goes with the steps whose span ``(t - 4 ms, t]``
    holds a multiple of 5 ms, wherever in the free run (paced by the wall clock)
    SET_MESSAGE_INTERVAL arrived: sessions in lockstep send it at the same steps. (It was
    anchored where the command arrived: two sessions that started lockstep at the same step
    differed in which steps carried it.)"""
    server, plant, port = served
    sock, mav = _raw(port)
    sock.sendall(common.MAVLink_heartbeat_message(common.MAV_TYPE_QUADROTOR, common.MAV_AUTOPILOT_PX4, 0, 0, 0,
                                                  3).pack(mav))  # the free run starts
    while _read_until(sock, mav, "HIL_SENSOR").time_usec < 12000:  # a few free-run steps go by
        pass
    sock.sendall(common.MAVLink_command_long_message(0, 0, common.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                                     common.MAVLINK_MSG_ID_HIL_STATE_QUATERNION, 5000, 0, 0, 0, 0,
                                                     0).pack(mav)
                 + common.MAVLink_hil_actuator_controls_message(0, [0.0] * 16, 1, 1).pack(mav))
    sensors, states = [], []
    deadline = time.monotonic() + 10
    while len(sensors) < 60 and time.monotonic() < deadline:
        for m in mav.parse_buffer(sock.recv(65536)) or ():
            if m.get_type() == "HIL_SENSOR":
                sensors.append(m.time_usec)
                sock.sendall(common.MAVLink_hil_actuator_controls_message(0, [0.0] * 16, 1, 1).pack(mav))
            elif m.get_type() == "HIL_STATE_QUATERNION":
                states.append(m.time_usec)
    sock.close()
    window = sensors[-40:]  # well after the command: in lockstep
    assert len(window) == 40 and all(t1 - t0 == 4000 for t0, t1 in zip(window, window[1:]))
    assert [t for t in states if t >= window[0]] == [t for t in window if t // 5000 > (t - 4000) // 5000]
