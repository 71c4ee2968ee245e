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
