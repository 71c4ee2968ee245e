"""The plant a flight stack flies in lockstep: the rig with its own controllers off.

:class:`LockstepPlant` wraps the served :class:`~rig_emulator.simulation.live.LiveRig`: the
flight stack's motor commands go straight to the motor drivers (the ``external`` controller
mode of the step loop: no guidance, no control law, no allocation), and each
:meth:`LockstepPlant.advance` runs one step of the flight stack's rate (``rate_hz``, a
sub-multiple of the physics rate: 250 Hz = 4 physics steps at 1 kHz) and returns that
step's :class:`~rig_emulator.simulation.hil_readout.HilReadout`.

Everything else of the rig runs as always: physics, the IMU modules and load cells with
their noise, the rig's calibration, ensemble, complementary filter and load-cell filter
(the ground link reports them), injected faults. The loss-of-control supervisor only
reports (``failsafe.action = "report"``): the flight stack owns the motors, and the
rig's own arming follows the flight stack's (armed while it commands any motor).

:meth:`LockstepPlant.restart` starts the plant afresh from the rig's current configuration
(parameters set over the ground link included): time 0, the initial position and attitude,
motors off, the same seed, so that every session of a flight stack is the same run.
"""

from __future__ import annotations

from rig_emulator.config.loader import ConfigError
from rig_emulator.physics import state as S
from rig_emulator.simulation.hil_readout import HilReadout, hil_readout
from rig_emulator.simulation.run import Simulation

#: keys the lockstep plant sets over the rig's configuration
LOCKSTEP_OVERRIDES = {"failsafe.action": "report"}


class LockstepPlant:
    def __init__(self, rig, rate_hz: float, home_alt_m: float, rate_option: str = "--px4-rate"):
        physics_hz = rig.cfg["sim.physics_rate_hz"]
        ratio = physics_hz / rate_hz if rate_hz > 0 else 0.0
        if not (rate_hz > 0 and abs(ratio - round(ratio)) < 1e-9 and round(ratio) >= 1):
            raise ConfigError(f"{rate_option} {rate_hz:g}: must divide the physics rate "
                              f"(sim.physics_rate_hz = {physics_hz:g}), e.g. 250, 500 or 1000")
        self.rig = rig
        self.rate_hz = float(rate_hz)
        self.steps_per_update = int(round(ratio))
        self.home_alt_m = float(home_alt_m)
        self._velocity_prev = (0.0, 0.0, 0.0)
        self._armed = False

    @property
    def period_s(self) -> float:
        return self.steps_per_update * self.rig.dt

    @property
    def time_s(self) -> float:
        return self.rig.time_s

    @property
    def voltage_max_v(self) -> float:
        return float(self.rig.cfg["motors.voltage_max"])

    def restart(self) -> None:
        """A fresh plant from the rig's configuration (time 0, motors off): the served rig's
        simulation is replaced by one whose motors are commanded from outside."""
        rig = self.rig
        cfg = rig.cfg.with_overrides(LOCKSTEP_OVERRIDES)
        sim = Simulation(cfg, log_capacity=rig.chunk_steps_max + 1, external_motors=True)
        sim.armed = False
        sim.warm_up()
        rig.sim = sim
        self._velocity_prev = tuple(sim.x[S.VEL:S.VEL + 3].tolist())
        self._armed = False

    def command(self, voltages, armed: bool) -> None:
        """Hold these motor voltage commands (V, motors 1..4) from the next step on (armed:
        the motor drivers are enabled; disarmed, the loop holds 0 V)."""
        sim = self.rig.sim
        v_cmd, v_max = sim.v_cmd, sim.pp.v_max
        for i in range(4):  # sim.set_motor_voltages without its array checks: a call per step
            v = voltages[i]
            v_cmd[i] = 0.0 if not v > 0.0 else (v if v < v_max else v_max)
        if armed != self._armed:
            self._armed = armed
            sim.armed = armed

    def advance(self) -> HilReadout:
        """One step of the flight stack's rate; the readout at its end."""
        sim = self.rig.sim
        k_prev = sim.k
        v_prev = self._velocity_prev
        self.rig.step(self.steps_per_update)
        out = hil_readout(sim, k_prev, v_prev, self.home_alt_m)
        self._velocity_prev = out.velocity
        return out
