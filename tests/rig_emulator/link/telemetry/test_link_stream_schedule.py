"""Default streams start staggered, so that no service period builds them all at once
(rig_emulator/link/telemetry/streams.py); rates stay exact and requested rates start at once."""

from collections import Counter

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry.stream_table import default_rates
from rig_emulator.link.telemetry.streams import StreamSchedule

CHUNK = 0.005


def _run(schedule, t0, seconds):
    per_chunk, counts = [], Counter()
    for k in range(int(round(seconds / CHUNK))):
        due = schedule.due(t0 + k * CHUNK)
        per_chunk.append(len(due))
        counts.update(due)
    return per_chunk, counts


def test_default_streams_never_fall_due_together_and_keep_their_rates():
    rates = default_rates()
    per_chunk, counts = _run(StreamSchedule(rates, CHUNK), t0=12.345, seconds=10.0)
    # without the stagger every stream fell due in the same chunk once per simulated second
    assert max(per_chunk) <= 3 < len(rates)
    for msg_id, hz in rates.items():
        assert abs(counts[msg_id] - hz * 10.0) <= 1, (msg_id, counts[msg_id])


def test_every_default_stream_starts_within_its_first_interval():
    rates = default_rates()
    s = StreamSchedule(rates, CHUNK)
    first = {}
    for k in range(1000):
        for msg_id in s.due(50.0 + k * CHUNK):
            first.setdefault(msg_id, k * CHUNK)
    assert set(first) == set(rates)
    for msg_id, hz in rates.items():
        assert first[msg_id] < 1.0 / hz + 1e-9


def test_a_requested_rate_starts_at_once():
    s = StreamSchedule(default_rates(), CHUNK)
    s.set_rate(M.MAVLINK_MSG_ID_HOME_POSITION, 1.0, now=3.0)
    assert M.MAVLINK_MSG_ID_HOME_POSITION in s.due(3.0)
    s.due(3.005)
    s.set_rate(M.MAVLINK_MSG_ID_SYSTEM_TIME, 2.0, now=3.01)  # after the first service too
    assert M.MAVLINK_MSG_ID_SYSTEM_TIME in s.due(3.01)


def test_requested_streams_of_one_rate_fall_due_together_whenever_each_was_asked_for():
    """An identification log's rows: ATTITUDE, SERVO_OUTPUT_RAW and HILMS_LOAD_CELLS asked for at 100 Hz one
    service period apart share every due period after their first message, also after the loop ran late."""
    ids = (M.MAVLINK_MSG_ID_ATTITUDE, M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW, M.MAVLINK_MSG_ID_HILMS_LOAD_CELLS)
    s = StreamSchedule(default_rates(), CHUNK)
    t0 = 7.0
    asked = dict(zip(ids, (0, 1, 3)))  # one request per service period
    due_at = {msg_id: [] for msg_id in ids}
    for k in range(2000):
        now = t0 + k * CHUNK
        for msg_id, k_asked in asked.items():
            if k == k_asked:
                s.set_interval(msg_id, 10_000, now)
        if 500 <= k < 510:  # the loop ran late: these periods are never serviced
            continue
        for msg_id in s.due(now):
            if msg_id in due_at and k >= asked[msg_id]:
                due_at[msg_id].append(round(now, 6))
    firsts = [due_at[i][0] for i in ids]
    assert firsts == [round(t0 + k * CHUNK, 6) for k in (0, 1, 3)]  # each starts at once
    rows = [[t for t in due_at[i] if t > max(firsts)] for i in ids]  # once all three stream
    assert rows[0] == rows[1] == rows[2]
    assert len(rows[0]) >= 985  # 100 Hz over 10 s, less the 50 ms not serviced
