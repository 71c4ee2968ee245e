"""A command acts once however often it arrives: a retry (confirmation incremented, as the command
protocol prescribes) is ACKed with the first result without acting again; a duplicated frame or
a first transmission overtaken by its retry neither acts nor gets a second ACK; a new
transmission (confirmation 0, new sequence number) acts. Shocks outside
the config's ranges are refused with the reason."""

import math

import pytest

from protocol.dialect import mavlink as M
from rig_emulator.testing.rig import RigThread, connect, recv

NAN = math.nan


@pytest.fixture(scope="module")
def rig_and_calls():
    with RigThread(speedup=4.0) as rig:
        calls = []
        original = rig.server.rig.apply_shock

        def counting(*args):
            calls.append(args)
            return original(*args)

        rig.server.rig.apply_shock = counting
        yield rig, calls


def _shock_frame(mav, torque, confirmation=0):
    msg = M.MAVLink_command_long_message(1, 1, M.MAV_CMD_HILMS_SHOCK, confirmation, 1, torque, 0.5, NAN, NAN, NAN, NAN)
    frame = bytes(msg.pack(mav))
    mav.seq = (mav.seq + 1) % 256
    return frame


def _acks(conn, n, absent=0):
    """The next ``n`` shock ACKs' results; the last ``absent`` are expected not to come, so they
    are waited for 2 s, the others up to 15 s (a loaded machine may take seconds to answer)."""
    out = [recv(conn, "COMMAND_ACK", 2.0 if i >= n - absent else 15.0, lambda m: m.command == M.MAV_CMD_HILMS_SHOCK)
           for i in range(n)]
    return [None if a is None else a.result for a in out]


def test_duplicates_and_retries_act_once(rig_and_calls):
    rig, calls = rig_and_calls
    conn = connect(rig.tcp_url)
    mav = M.MAVLink(None, srcSystem=255, srcComponent=190)
    try:
        first = _shock_frame(mav, 1.5)
        conn.port.sendall(first + first)  # one frame delivered twice: one action, one ACK
        assert _acks(conn, 1) == [M.MAV_RESULT_ACCEPTED]
        assert [c[1] for c in calls] == [1.5]
        conn.port.sendall(_shock_frame(mav, 1.5, confirmation=1) + _shock_frame(mav, 1.5, confirmation=2))  # retries
        assert _acks(conn, 2) == [M.MAV_RESULT_ACCEPTED] * 2  # each retry is answered, none acts
        assert [c[1] for c in calls] == [1.5]
        conn.port.sendall(_shock_frame(mav, 1.5))  # sent again on purpose: a new transmission
        assert _acks(conn, 1) == [M.MAV_RESULT_ACCEPTED]
        assert [c[1] for c in calls] == [1.5, 1.5]
        assert _acks(conn, 1, absent=1) == [None]  # no ACK for the duplicated frame came after all
        assert rig.server.counters.dropped["duplicate_command"] == 3
    finally:
        conn.close()


@pytest.mark.parametrize("torque, duration, reason", [(1e30, 0.5, "torque"), (150.0, 0.5, "torque"),
                                                      (1.0, 60.0, "duration"), (1.0, -1.0, "duration")])
def test_shock_outside_the_config_ranges_is_denied(rig_and_calls, torque, duration, reason):
    rig, calls = rig_and_calls
    conn = connect(rig.tcp_url)
    try:
        n = len(calls)
        conn.mav.command_long_send(1, 1, M.MAV_CMD_HILMS_SHOCK, 0, 2, torque, duration, NAN, NAN, NAN, NAN)
        assert _acks(conn, 1) == [M.MAV_RESULT_DENIED]
        text = recv(conn, "STATUSTEXT", 5.0, lambda m: "shock rejected" in m.text).text
        assert reason in text, text
        assert len(calls) == n
    finally:
        conn.close()


def test_a_first_transmission_arriving_after_its_retry_does_not_act_again(rig_and_calls):
    rig, calls = rig_and_calls
    conn = connect(rig.tcp_url)
    mav = M.MAVLink(None, srcSystem=255, srcComponent=190)
    try:
        n = len(calls)
        original = _shock_frame(mav, 2.5)
        retry = _shock_frame(mav, 2.5, confirmation=1)
        conn.port.sendall(retry + original)  # re-ordered by the link: the retry acts and is answered
        assert _acks(conn, 1) == [M.MAV_RESULT_ACCEPTED]
        assert [c[1] for c in calls[n:]] == [2.5]
        conn.port.sendall(_shock_frame(mav, 2.5))  # a later first transmission: a new command
        assert _acks(conn, 1) == [M.MAV_RESULT_ACCEPTED]
        assert [c[1] for c in calls[n:]] == [2.5, 2.5]
    finally:
        conn.close()


def test_back_to_back_calibrations_are_refused(rig_and_calls):
    """Each calibration blocks the loop for about 0.1 s: a flood of them must not stall control."""
    rig, _ = rig_and_calls
    conn = connect(rig.tcp_url)
    try:
        results = []
        for _ in range(3):
            conn.mav.command_long_send(1, 1, M.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 1, 0, 0, 0, 0, 0, 0)
            results.append(recv(conn, "COMMAND_ACK", 10.0, lambda m: m.command == M.MAV_CMD_PREFLIGHT_CALIBRATION).result)
        assert results == [M.MAV_RESULT_ACCEPTED] + [M.MAV_RESULT_TEMPORARILY_REJECTED] * 2
    finally:
        conn.close()


def test_a_retry_arriving_after_the_next_command_does_not_act_again(rig_and_calls):
    """The sender got its ACK and moved on; a retry the link held back arrives after the next command."""
    rig, calls = rig_and_calls
    conn = connect(rig.tcp_url)
    mav = M.MAVLink(None, srcSystem=255, srcComponent=190)
    try:
        n = len(calls)
        first, retry = _shock_frame(mav, 3.25), _shock_frame(mav, 3.25, confirmation=1)
        conn.port.sendall(first)
        assert _acks(conn, 1) == [M.MAV_RESULT_ACCEPTED]
        conn.port.sendall(_shock_frame(mav, 3.5) + retry)
        assert _acks(conn, 2, absent=1) == [M.MAV_RESULT_ACCEPTED, None]  # 3.5 answered; the stale retry neither acts nor is answered
        assert [c[1] for c in calls[n:]] == [3.25, 3.5]
    finally:
        conn.close()
