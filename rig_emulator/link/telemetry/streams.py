"""Per-peer stream schedules counted in simulated time.

Each streamed message has an interval (s of simulated time; 0 = off). A message is due
when the simulated clock reaches its next due time; the next due time then advances by
one interval, so the average rate is exact even when the link is serviced in chunks.
Intervals shorter than the service period are raised to it (the link cannot emit more
often than it runs).

The default streams start staggered: the i-th stream of the table first falls due
``i`` service periods (modulo its interval) after the peer's first service, so that
streams whose rates divide one another do not all fall due in the same service period
(building all of them at once cost ~2 ms of CPU every simulated second, which delayed the
physics under load). A rate set later (MAV_CMD_SET_MESSAGE_INTERVAL, REQUEST_DATA_STREAM)
starts at once, and from its second message on falls due on its interval's grid of simulated
time (the multiples of the interval, counted from t = 0), also after the loop ran late: streams
a peer asked for at one rate (or at rates that divide one another) fall due in the same service
period, so their messages are built from one snapshot and share their time stamp, whenever each
was asked for. (An identification log needs ATTITUDE, SERVO_OUTPUT_RAW and HILMS_LOAD_CELLS rows
at one stamp, gcs_tools/identify/sysid_log.py: at 100 Hz with 5 ms service periods, requests a
period apart would otherwise have kept their streams 5 ms apart for good.)
"""

from __future__ import annotations

import math

EPS_S = 1e-9


class StreamSchedule:
    def __init__(self, default_hz: dict[int, float], min_interval_s: float):
        self.default_hz = dict(default_hz)
        self.min_interval_s = min_interval_s
        self.interval_s: dict[int, float] = {}
        self.next_due: dict[int, float] = {}
        self._start_offsets: dict[int, float] = {}
        self._on_grid: set[int] = set()  # streams a peer set: due on their interval's grid of simulated time
        for msg_id, hz in self.default_hz.items():
            self.set_rate(msg_id, hz, now=0.0, grid=False)
        # first due time of each default stream, relative to the first call of due()
        self._start_offsets = {msg_id: (i * min_interval_s) % interval if interval > 0.0 else 0.0
                               for i, (msg_id, interval) in enumerate(self.interval_s.items())}

    def knows(self, msg_id: int) -> bool:
        return msg_id in self.default_hz

    def set_rate(self, msg_id: int, hz: float, now: float, grid: bool = True) -> float:
        """Stream ``msg_id`` at ``hz`` (0 = off) from ``now`` on, after its first message on the interval's
        grid (``grid``; the constructor's default rates are staggered instead); returns the interval in
        effect (s)."""
        interval = 0.0 if hz <= 0.0 or not math.isfinite(hz) else max(1.0 / hz, self.min_interval_s)
        self.interval_s[msg_id] = interval
        self.next_due[msg_id] = now
        self._start_offsets.pop(msg_id, None)
        if grid:
            self._on_grid.add(msg_id)
        else:
            self._on_grid.discard(msg_id)
        return interval

    def set_interval(self, msg_id: int, interval_us: float, now: float) -> float:
        """MAV_CMD_SET_MESSAGE_INTERVAL semantics: -1 off, 0 default, else microseconds."""
        if interval_us == 0:
            return self.set_rate(msg_id, self.default_hz[msg_id], now)
        if interval_us < 0:
            return self.set_rate(msg_id, 0.0, now)
        return self.set_rate(msg_id, 1e6 / interval_us, now)

    def interval_us(self, msg_id: int) -> int:
        """MESSAGE_INTERVAL semantics: -1 off, else microseconds."""
        interval = self.interval_s.get(msg_id, 0.0)
        return -1 if interval <= 0.0 else int(round(interval * 1e6))

    def clock_restarted(self, t_old: float, t_new: float = 0.0) -> None:
        """The simulated clock jumped back from ``t_old`` to ``t_new`` (a reboot, a new session of a
        flight stack in the loop): every next due time moves back by the jump (none before
        ``t_new``), so the streams carry on at their rates instead of waiting for ``t_old``."""
        shift = t_old - t_new
        next_due = self.next_due
        for msg_id in next_due:
            next_due[msg_id] = max(t_new, next_due[msg_id] - shift)

    def due(self, now: float) -> list[int]:
        """Message ids due at simulated time ``now``; advances their schedules."""
        if self._start_offsets:
            for msg_id, offset in self._start_offsets.items():
                self.next_due[msg_id] = now + offset
            self._start_offsets = {}
        out = []
        next_due = self.next_due
        on_grid = self._on_grid
        late = now + EPS_S
        for msg_id, interval in self.interval_s.items():
            due_at = next_due[msg_id]
            if late < due_at or interval <= 0.0:
                continue
            out.append(msg_id)
            if msg_id in on_grid:  # the first multiple of the interval after now
                next_due[msg_id] = (math.floor(late / interval) + 1) * interval
                continue
            nxt = due_at + interval
            next_due[msg_id] = nxt if nxt + EPS_S > now else now + interval
        return out
