"""A headless rig: arrays for the compiled loop, initial conditions, and the run's results."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from protocol.mean_error import mean_errors
from rig_emulator.config.loader import RigConfig
from rig_emulator.control.controller import CS_SIZE, OUT_SIZE, REF_SIZE
from rig_emulator.guidance.runner import GS_SIZE
from rig_emulator.physics import state as S
from rig_emulator.physics.motors import voltage_for_thrust
from rig_emulator.physics.rotation import quat_from_euler
from rig_emulator.simulation import log_layout as L
from rig_emulator.control.supervisor import F_FAILSAFE, reset_failsafe, supervisor_params, supervisor_state
from rig_emulator.simulation.faults import FaultEvent, FaultInjector, FaultStatus, fault_status
from rig_emulator.simulation import rng_bits
from rig_emulator.guidance.sysid import SysidProgramme
from rig_emulator.simulation.entry_points import BoundEntry
from rig_emulator.simulation.loop import run_steps
from rig_emulator.control.plugin_layout import P_EXTERNAL
from rig_emulator.simulation.plugin import plugin_binding, unreported_attitude
from rig_emulator.simulation.sensing import build_sensing
from rig_emulator.simulation.params import control_params, disturbances, guidance_params, physics_params


def step_time_us(k: int, rate_hz: float) -> int:
    """Time of physics step ``k`` at ``rate_hz`` in whole microseconds (exact for integer rates)."""
    rate = float(rate_hz)
    if rate.is_integer():
        return (int(k) * 1_000_000) // int(rate)
    return int(round(int(k) * 1_000_000 / rate))


def last_update_us(k: int, div: int, rate_hz: float) -> int:
    """Time, in whole microseconds, of the last step at or before step ``k`` of something that runs
    every ``div`` physics steps from step 0 (a control update, a load-cell sample): what a value
    it produced and a later message carries was taken at."""
    return step_time_us(int(k) // div * div, rate_hz)


@dataclass
class SimResult:
    """What a headless run produced: the recorded time series and its figures."""

    config: RigConfig
    log: np.ndarray
    reached_t: np.ndarray
    steps: int
    sim_time_s: float
    wall_time_s: float
    series: dict = field(init=False)
    #: physics steps per control update (the config's control rate, or the plug-in's) and per
    #: load-cell sample, as the run used them: when the logged commands and readings were taken
    control_div: int = 1
    cells_div: int = 1

    def __post_init__(self):
        self.series = {name: self.column(name) for name in L.NAMES}

    def column(self, name: str) -> np.ndarray:
        start, width = L.NAMES[name]
        return self.log[:, start] if width == 1 else self.log[:, start : start + width]

    @property
    def real_time_factor(self) -> float:
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else math.inf

    def mean_errors(self, window: tuple[float, float] | None = None) -> dict[str, float]:
        """Eq. 45 for phi, theta, psi (deg) and X, Y, Z (m) over the run (or a window)."""
        s = self.series
        return mean_errors(s["t"], s["euler"], s["euler_des"], s["pos"], s["pos_des"], window)


class Simulation:
    """One rig built from a validated config; :meth:`advance` runs the compiled loop in chunks."""

    def __init__(self, cfg: RigConfig, log_capacity: int | None = None, controller=None,
                 external_motors: bool = False):
        """``controller``: a controller plug-in (``"module:Name"``, a class or an instance of
        :class:`rig_emulator.controllers.Controller`; default: the config's
        ``controller.plugin``, none when empty). ``external_motors``: no controller at all, the
        motor voltages are set with :meth:`set_motor_voltages` between calls (lockstep)."""
        self.cfg = cfg
        self.dt = 1.0 / cfg["sim.physics_rate_hz"]
        self.ctrl_div = int(round(cfg["sim.physics_rate_hz"] / cfg["sim.control_rate_hz"]))
        self.log_div = int(round(cfg["sim.physics_rate_hz"] / cfg["sim.log_rate_hz"]))
        self.pp = physics_params(cfg)
        self.cp = control_params(cfg)
        self.gp = guidance_params(cfg)
        self.dist = disturbances(cfg)
        self.sensing = build_sensing(cfg, self.dt)
        suite = self.sensing.params.suite
        self.plugin = plugin_binding(cfg, self.cp, suite.imu.n_modules, controller, external_motors)
        self.plugin_failure = None  # PluginError of the plug-in's failure while armed
        if self.plugin.ctrl_div is not None:
            self.ctrl_div = self.plugin.ctrl_div  # the plug-in sets the onboard loop's period
        self.up = self.supervisor_params(cfg)
        self.us = supervisor_state(suite.imu.n_modules, suite.cells.n_cells)
        self.faults = FaultInjector(self)
        self._pending_faults = self.faults.schedule(cfg)
        self.x = np.zeros(S.SIZE)
        self.x[S.POS : S.POS + 3] = cfg["initial.position"]
        phi, theta, psi = (math.radians(a) for a in cfg["initial.euler_deg"])
        quat_from_euler(phi, theta, psi, self.x[S.QUAT : S.QUAT + 4])
        self.sensing.state.onboard[0:3] = cfg["initial.position"]
        hover_v = voltage_for_thrust(self.pp.mass * self.pp.g / 4.0, self.pp.k_v, self.pp.v_max)
        self.x[S.MOTOR_V : S.MOTOR_V + 4] = hover_v
        self.v_cmd = np.full(4, hover_v)
        self.pp.hw.cmd_buf[:] = hover_v  # a delayed actuator starts from the hover command too
        self.cstate = np.zeros(CS_SIZE)
        self.gstate = np.zeros(GS_SIZE)
        self.reached_t = np.full(self.gp.waypoints.shape[0], np.nan)
        self.ref = np.zeros(REF_SIZE)
        self.cout = np.zeros(OUT_SIZE)
        if external_motors:
            unreported_attitude(self.cout)
        self.scratch = np.zeros((5, 3))
        self.work = np.zeros((5, S.SIZE))
        self.R = np.zeros((3, 3))
        n_steps = int(round(cfg["sim.duration"] / self.dt))
        if log_capacity is None:
            log_capacity = n_steps // self.log_div + 1
        self.log = np.full((log_capacity, L.NCOLS), np.nan)
        self.log_row = 0
        self.k = 0
        self._armed = True
        self._loop = BoundEntry(run_steps)  # the step loop's entry point for this rig's objects
        self._rng_held = None  # (bit generator, its pointers): _rng_pointers
        self.programme = SysidProgramme(self) if cfg["guidance.type"] == "sysid" else None

    @property
    def time(self) -> float:
        return self.k * self.dt

    @property
    def time_us(self) -> int:
        """Simulated time in whole microseconds, from the integer step counter (what message
        time stamps are derived from: no float clock, no rounding down of k dt)."""
        return step_time_us(self.k, self.cfg["sim.physics_rate_hz"])

    def supervisor_params(self, cfg: RigConfig):
        """The supervisor's arguments for ``cfg`` (health thresholds, failsafe) on this rig's sensors."""
        imu = self.sensing.params.suite.imu
        return supervisor_params(cfg, imu.n_modules, imu.gravity_m_s2, float(np.linalg.norm(imu.earth_field_W)),
                                 self.dt * self.ctrl_div, self.ctrl_div)

    @property
    def armed(self) -> bool:
        return self._armed

    @armed.setter
    def armed(self, value: bool) -> None:
        """Arming clears a latched failsafe (and its timers); disarming keeps it for the record."""
        if value:
            reset_failsafe(self.us)
            self.plugin.clear()
            self.plugin_failure = None
        self._armed = bool(value)

    def advance(self, n_steps: int) -> None:
        """Run ``n_steps`` physics steps, switching the config's timed faults on at their step
        (the loop is called in pieces between them, which changes nothing else); the
        identification flight (``guidance.type = "sysid"``) sets its set-point before each of its
        update periods (guidance/sysid.py)."""
        if self.programme is None or n_steps == 0:  # 0: a warm-up still calls (compiles) the loop
            if self.programme is not None:
                self.programme.apply(self)
            self._advance_faults(n_steps)
            return
        for _, n in self.programme.pieces(self.k, n_steps):
            self.programme.apply(self)
            self._advance_faults(n)

    def _advance_faults(self, n_steps: int) -> None:
        end = self.k + n_steps
        while self._pending_faults and self._pending_faults[0][0] < end:
            k_event, e = self._pending_faults.pop(0)
            if k_event > self.k:
                self._advance(k_event - self.k)
            self.faults.inject(e["sensor"], e["index"], e["mode"], e["magnitude"], source="config")
        self._advance(end - self.k)

    def _advance(self, n_steps: int) -> None:
        """Run ``n_steps`` physics steps through the compiled loop.

        numba's dispatcher types every argument on every call, and namedtuples take its slow
        Python path (about 0.2 ms a call here): a rig stepped in 5 ms chunks would spend more
        time being dispatched than simulated. So the compiled entry point for these argument
        types is looked up once and called directly; it is looked up again whenever one of the
        parameter objects is replaced (a parameter change, a new mission, ...). The lookup
        itself uses a structural key of the arguments, not numba's typing
        (:mod:`rig_emulator.simulation.entry_points`): a new rig of a known shape finds its
        entry point in tens of microseconds instead of milliseconds.
        """
        d = self.dist
        args = (
            self.k, n_steps, self.dt, self.ctrl_div, self.log_div,
            self.x, self.v_cmd, self.pp, self.cp, self.gp, d.wind, d.gusts, d.shocks, d.extra,
            self.cstate, self.gstate, self.reached_t, self.ref, self.cout, self.scratch, self.work, self.R,
            self.log, self.log_row, bool(self._armed),
            self.sensing.params, self.sensing.state, self._rng_pointers(), self.up, self.us,
            self.plugin.params, self.plugin.fn,
        )
        # the scalars between the objects (log_row, armed) are left out of the lookup's key
        self.log_row = self._loop(args, args[5:23] + args[25:])(*args)
        self.k += n_steps
        if self.plugin.params.status[0] != 0 and self.plugin_failure is None:
            self._plugin_failed()
        if self._armed and self.up.fs_disarm and self.us.flags[F_FAILSAFE] != 0:
            self._armed = False  # the failsafe cut the motors inside the loop; the rig stays disarmed

    def _rng_pointers(self) -> tuple:
        """The sensors' bit generator as the loop takes it (:func:`rng_bits.pointers`), read once
        per bit generator (the sensing may be replaced); the bit generator is held with them."""
        bits = self.sensing.run_rng.bit_generator
        held = self._rng_held
        if held is None or held[0] is not bits:
            held = self._rng_held = (bits, rng_bits.pointers(bits))
        return held[1]

    def __getstate__(self) -> dict:
        """A copy (``copy.deepcopy``, pickle) reads its own bit generator's pointers again: the
        copied ones would point into the original's memory."""
        return {**self.__dict__, "_rng_held": None}

    def _plugin_failed(self) -> None:
        """The plug-in failed inside the loop, which disarmed: keep the rig disarmed and the reason."""
        self._armed = False
        exc = self.plugin.exc
        if isinstance(exc, (KeyboardInterrupt, SystemExit)):
            self.plugin.clear()
            raise exc
        self.plugin_failure = self.plugin.failure(self.dt)

    def set_motor_voltages(self, volts) -> None:
        """Motor voltages 1-4 (V, clipped to the supply) held from the next step on; only a rig
        built with ``external_motors=True`` (lockstep). Disarmed, the loop holds 0 V."""
        if self.plugin.params.mode != P_EXTERNAL:
            raise ValueError("motor commands from outside need a rig built with external_motors=True")
        v = np.asarray(volts, dtype=np.float64)
        if v.shape != (4,) or not np.all(np.isfinite(v)):
            raise ValueError(f"expected 4 finite motor voltages, got {volts!r}")
        np.clip(v, 0.0, self.pp.v_max, out=self.v_cmd)

    def set_motor_thrusts(self, thrusts) -> None:
        """Motor thrusts 1-4 (N) held from the next step on, as voltages by Eq. 40 (see
        :meth:`set_motor_voltages`)."""
        f = np.asarray(thrusts, dtype=np.float64)
        if f.shape != (4,) or not np.all(np.isfinite(f)):
            raise ValueError(f"expected 4 finite motor thrusts, got {thrusts!r}")
        self.set_motor_voltages(f / self.pp.k_v)

    def warm_up(self) -> float:
        """Compile (or load from cache) the loop without advancing it; returns the seconds it took."""
        t0 = time.perf_counter()
        self.advance(0)
        return time.perf_counter() - t0

    def set_fault(self, device: str, index: int, mode: str, magnitude: float = 0.0) -> FaultEvent:
        """Switch IMU module ``index`` (0..4, ``device='imu'``), load cell or motor ``index``
        (1..4, ``'load_cell'``, ``'motor'``) into a fault mode now (``'none'`` clears it).

        Raises ValueError with the reason (unknown device or mode, index or magnitude out of
        range); the rig is unchanged then.
        """
        return self.faults.inject(device, index, mode, magnitude)

    def fault_status(self) -> FaultStatus:
        return fault_status(self)

    def run(self, duration: float | None = None) -> SimResult:
        """Run the whole configured duration (or ``duration``) headless, as fast as possible.

        The configured ``faults.events`` are switched on at their times (:meth:`advance`).
        """
        self.warm_up()
        n_steps = int(round((self.cfg["sim.duration"] if duration is None else duration) / self.dt))
        t0 = time.perf_counter()
        self.advance(n_steps)
        wall = time.perf_counter() - t0
        if self.plugin_failure is not None:
            raise self.plugin_failure
        return SimResult(
            config=self.cfg,
            log=self.log[: self.log_row].copy(),
            reached_t=self.reached_t.copy(),
            steps=n_steps,
            sim_time_s=n_steps * self.dt,
            wall_time_s=wall,
            control_div=self.ctrl_div,
            cells_div=self.sensing.params.suite.cells.decim,
        )
