"""The ground link beside a flight stack in the loop (PX4's Simulator MAVLink API, ArduPilot's
JSON interface): the rig's own MAVLink server serviced between the flight stack's steps.

The flight stack steps the plant; the ground link (:class:`~rig_emulator.link.server.RigServer`:
HEARTBEAT, the rig's telemetry and load cells, parameters, commands) is serviced between
steps at most every :data:`GROUND_PERIOD_S` of wall-clock time, or at once when a ground
station sent something. Its streams are scheduled in simulated time as always; a plant
stepped at 10x real time thins them to one message per service (as ``--speedup max`` does).

Each session of a flight stack starts the plant afresh (its clock back to 0): the ground
stations' stream schedules, kept in simulated time, are moved back with it
(:meth:`GroundBeside.plant_restarted`), or a ground station that connected during an earlier
session would wait for the old session's time to come round again before its streams resumed.
"""

from __future__ import annotations

GROUND_PERIOD_S = 0.01


class GroundBeside:
    def __init__(self, ground):
        self.ground = ground
        self.next_at = 0.0  # wall-clock time of the next service

    def service(self, now: float) -> None:
        """Heartbeat when due, read and act on what the ground stations sent, report faults, the
        streams due at the plant's simulated time, and hand everything to the sockets."""
        g = self.ground
        self.next_at = now + GROUND_PERIOD_S
        g._snap = None  # the plant moved since: the ground link's cached snapshot is stale
        g._heartbeat_if_due(now)
        g.service_io()
        g.report_faults()
        g.emit_streams()
        g.flush()

    def sockets(self) -> list:
        """The ground link's sockets to wait on (they change as ground stations come and go)."""
        return [s for ep in self.ground.endpoints for s in ep.filenos()]

    def plant_restarted(self, t_old: float) -> None:
        """The plant started afresh (a new session) from simulated time ``t_old``."""
        self.ground.clock_restarted(t_old)
