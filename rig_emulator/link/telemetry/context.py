"""What the message builders need besides the snapshot: the rig's parameters, home, the
sensor model, the flight mode and the link's own health figures."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from protocol.geodesy import Home
from rig_emulator.link.endpoints.counters import LinkCounters
from rig_emulator.link.telemetry.ideal_sensors import SensorModel, SensorReadings, sensor_readings
from rig_emulator.link.commands.modes import FlightModes


@dataclass
class TelemetryContext:
    rig: object  # LiveRig: builders read rig.cfg only, never command
    home: Home
    sensors: SensorModel
    modes: FlightModes
    counters: LinkCounters
    sysid: int
    mission: object = None  # MissionExecutor: MISSION_CURRENT's builder reads it
    fence: object = None  # FenceMonitor (flight_monitors.py): SYS_STATUS's GEOFENCE bits, FENCE_STATUS
    flight: object = None  # FlightControl: home and the flight task (HOME_POSITION, EXTENDED_SYS_STATE)
    load_fraction: float = 0.0  # share of wall time the loop spends working (SYS_STATUS.load)
    boot_unix_s: float = field(default_factory=time.time)
    _cache: tuple = (None, None)

    @property
    def cfg(self):
        return self.rig.cfg

    def readings(self, snap) -> SensorReadings:
        """The sensor readings of ``snap`` (computed once per snapshot)."""
        if self._cache[0] is not snap:
            self._cache = (snap, sensor_readings(snap, self.sensors, self.cfg["airframe.gravity"]))
        return self._cache[1]
