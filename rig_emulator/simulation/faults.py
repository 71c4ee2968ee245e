"""Fault injection into a rig and the plain-data fault status it reports.

:class:`FaultInjector` switches IMU modules, load cells and motors into the fault modes of
:mod:`rig_emulator.sensors.faults`, from the config's timed ``faults.events`` or from a
command, and keeps the list of every injection (:class:`FaultEvent`). :func:`fault_status`
reads what is injected and what the supervisor (:mod:`rig_emulator.control.supervisor`)
has detected into a :class:`FaultStatus`. No MAVLink here: the link layer maps these to
health bits and STATUSTEXT.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rig_emulator.config.loader import ConfigError
from rig_emulator.control import supervisor as SV
from rig_emulator.sensors.faults import (
    FAULT_MODES, FIRST_INDEX, check_fault, device_label, set_fault, thrust_efficiency)

N_MOTORS = 4


@dataclass(frozen=True)
class FaultEvent:
    """One injection (or clearing, mode 'none')."""

    time_s: float
    device: str  # 'imu', 'load_cell', 'motor'
    index: int  # IMU module from 0; load cell / motor = arm number 1..4
    mode: str
    magnitude: float
    source: str  # 'config' or 'command'

    @property
    def label(self) -> str:
        return device_label(self.device, self.index)


@dataclass(frozen=True)
class FaultStatus:
    """What is injected and what the rig's supervisor has detected, at one instant.

    Module masks have bit m for IMU module m; cell and motor masks bit i for arm i + 1.
    Sensor fields are empty / 0 when the sensor models are off.
    """

    imu_faults: tuple  # injected fault code per IMU module (HILMS_FAULT values)
    cell_faults: tuple  # per load cell
    motor_faults: tuple  # per motor: 0 none, 2 dead, 6 thrust_loss
    motor_thrust_loss: tuple  # fraction of thrust lost per motor (1.0 = dead)
    imu_flagged: tuple  # (gyro, accel, mag): modules the ensemble rejects (debounced)
    cells_flagged: int  # cells whose readings the guards reject (debounced)
    estimate_invalid: int  # fused estimate invalid: supervisor INVALID_* bits (1 gyro, 2 accel, 4 mag)
    alerts: int  # loss-of-control conditions beyond their limit now: supervisor ALERT_* bits
    failsafe: int  # latched cause of the loss-of-control failsafe (ALERT_* bits); 0 = not tripped
    failsafe_action: str  # 'disarm' or 'report'
    failsafe_time_s: float  # when it tripped (NaN while not tripped)
    failsafe_attitude_error: float  # roll/pitch error at the trip (rad)
    failsafe_rate: float  # body rate at the trip (rad/s)
    attitude_error: float  # latest roll/pitch error the supervisor saw (rad)
    events: int  # number of injections so far (FaultInjector.events)

    @property
    def imu_flagged_any(self) -> int:
        return self.imu_flagged[0] | self.imu_flagged[1] | self.imu_flagged[2] if self.imu_flagged else 0


def failsafe_cause_text(cause: int) -> str:
    """'attitude error, body rate' for the ALERT_* bits of ``cause``."""
    return ", ".join(name for bit, name in SV.ALERT_NAMES.items() if cause & bit) or "none"


class FaultInjector:
    """The fault arrays of one simulation and the log of injections."""

    def __init__(self, sim):
        self.sim = sim
        self.motor_faults = np.zeros(N_MOTORS, dtype=np.int64)
        self.motor_loss = np.zeros(N_MOTORS)
        self.events: list[FaultEvent] = []

    def n_units(self, device: str) -> int:
        suite = self.sim.sensing.params.suite
        return {"imu": suite.imu.n_modules, "load_cell": suite.cells.n_cells, "motor": N_MOTORS}.get(device, 0)

    def check(self, device: str, index: int, mode: str, magnitude: float) -> float:
        """Validate a fault for this rig (ValueError with the reason); returns its magnitude."""
        m = check_fault(device, index, mode, magnitude, self.n_units(device))
        if device != "motor" and not self.sim.sensing.params.simulate:
            raise ValueError("the sensor models are off (sensors.simulate = false)")
        return m

    def inject(self, device: str, index: int, mode: str, magnitude: float = 0.0, source: str = "command") -> FaultEvent:
        """Switch one device into ``mode`` now (``'none'`` clears it); ValueError if not possible."""
        magnitude = self.check(device, index, mode, magnitude)
        unit = int(index) - FIRST_INDEX[device]
        if device == "motor":
            self.motor_faults[unit] = FAULT_MODES[mode]
            self.motor_loss[unit] = 1.0 - thrust_efficiency(mode, magnitude)
            self.sim.pp.thrust_efficiency[unit] = thrust_efficiency(mode, magnitude)
        else:
            st = self.sim.sensing.state.sstate
            if device == "imu":
                set_fault(st.imu_fault_mode, st.imu_fault_magnitude, unit, mode, magnitude, imu=True)
            else:
                set_fault(st.cell_fault_mode, st.cell_fault_magnitude, unit, mode, magnitude, imu=False)
        event = FaultEvent(float(self.sim.time), device, int(index), mode, magnitude, source)
        self.events.append(event)
        return event

    def schedule(self, cfg) -> list[tuple[int, dict]]:
        """The config's ``faults.events`` as (physics step, event), in time order; checked now
        (ConfigError naming the event) so that a bad event fails before the run starts."""
        out = []
        for i, e in enumerate(cfg["faults.events"]):
            try:
                self.check(e["sensor"], e["index"], e["mode"], e["magnitude"])
            except ValueError as exc:
                raise ConfigError(f"faults.events[{i}]: {exc}") from None
            out.append((int(math.ceil(e["t"] / self.sim.dt - 1e-9)), e))
        out.sort(key=lambda ke: ke[0])
        return out


def fault_status(sim) -> FaultStatus:
    """The :class:`FaultStatus` of a :class:`~rig_emulator.simulation.run.Simulation` now."""
    return fault_status_of(*fault_status_inputs(sim))


def fault_status_inputs(sim) -> tuple:
    """What :func:`fault_status` reads of ``sim`` now, as plain values (``LiveRig.snapshot`` takes
    them per chunk and builds the status only when a message reads it)."""
    f = sim.faults
    v = sim.us.values
    sensed = sim.sensing.params.simulate
    st = sim.sensing.state.sstate
    return (sim.us.flags.tolist(), float(v[SV.V_TRIP_T]), float(v[SV.V_TRIP_ATT]), float(v[SV.V_TRIP_RATE]),
            float(v[SV.V_ATT_ERR]), sensed, st.imu_fault_mode.tolist() if sensed else None,
            st.cell_fault_mode.tolist() if sensed else None, f.motor_faults.tolist(), f.motor_loss.tolist(),
            bool(sim.up.fs_disarm), len(f.events))


def fault_status_of(flags, trip_t, trip_att, trip_rate, att_err, sensed, imu_modes, cell_modes, motor_faults,
                    motor_loss, fs_disarm, events) -> FaultStatus:
    """The :class:`FaultStatus` of the values :func:`fault_status_inputs` took."""
    tripped = int(flags[SV.F_FAILSAFE])
    return FaultStatus(
        imu_faults=tuple(map(int, imu_modes)) if sensed else (),
        cell_faults=tuple(map(int, cell_modes)) if sensed else (),
        motor_faults=tuple(map(int, motor_faults)),
        motor_thrust_loss=tuple(map(float, motor_loss)),
        imu_flagged=tuple(int(flags[SV.F_GYRO + s]) for s in range(3)) if sensed else (0, 0, 0),
        cells_flagged=int(flags[SV.F_CELLS]) if sensed else 0,
        estimate_invalid=int(flags[SV.F_INVALID]) if sensed else 0,
        alerts=int(flags[SV.F_ALERTS]),
        failsafe=tripped,
        failsafe_action="disarm" if fs_disarm else "report",
        failsafe_time_s=trip_t if tripped else math.nan,
        failsafe_attitude_error=trip_att,
        failsafe_rate=trip_rate,
        attitude_error=att_err,
        events=events,
    )
