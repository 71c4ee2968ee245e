"""The narrow interface between the running rig and its link layer (MAVLink, scripts).

The link layer never touches physics or control arrays: it steps the rig, reads a
:class:`RigSnapshot` (SI units, the paper's ENU/FRD frames) and commands through the
methods of :class:`LiveRig`. Conversions to MAVLink units and NED live in ``protocol/``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rig_emulator.config.loader import ConfigError, RigConfig
from rig_emulator.control.controller import (CS_TEST_UNTIL, CS_TEST_V, OUT_ATT_DES, OUT_ATT_RATE_DES, OUT_FLAGS, OUT_S,
                                             OUT_THRUST_CMD, OUT_U, REF_MODE, REF_POS, REF_VEL, REF_YAW)
from rig_emulator.guidance.offboard import (OFB_ATT, OFB_ACC, OFB_KIND, OFB_KIND_ATTITUDE, OFB_KIND_POSITION,
                                            OFB_KIND_RATES, OFB_POS, OFB_POS0, OFB_RATE, OFB_SIZE, OFB_T0, OFB_THRUST,
                                            OFB_VEL, OFB_YAW, OFB_YAW0, OFB_YAW_RATE, VELOCITY_TRACK_LEAD_M)
from rig_emulator.guidance.runner import (ATTITUDE, GS_DONE, GS_HOLD_UNTIL, GS_INDEX, GS_STARTED, HOVER, OFFBOARD,
                                          WAYPOINTS, start_at)
from rig_emulator.guidance.sysid import DURATION_S as SYSID_DURATION_S
from rig_emulator.guidance.sysid import SysidProgramme, part_of
from rig_emulator._jit import jit
from rig_emulator.physics import state as S
from rig_emulator.physics.hardware import motor_thrust, rest_attitude
from rig_emulator.physics.electrical import SEQUENTIAL_SUM_MAX, supply_current, supply_current_sum
from rig_emulator.physics.motors import GRAM_FORCE_N, rotor_speed
from rig_emulator.physics.rotation import euler_from_quat, euler_rates_from_body_rates, quat_from_euler, quat_to_rot
from rig_emulator.simulation.params import control_params, disturbances, guidance_params, physics_params
from rig_emulator.simulation.entry_points import BoundEntry
from rig_emulator.simulation.faults import FaultEvent, FaultStatus, fault_status_inputs, fault_status_of
from rig_emulator.simulation import log_layout as L
from rig_emulator.simulation.run import Simulation, last_update_us

# keys that fix array sizes or rates of a running rig
_RESTART_ONLY = ("sim.physics_rate_hz", "sim.control_rate_hz", "sim.log_rate_hz", "sim.seed", "controller.plugin",
                 "controller.call")


_GUIDANCE_NAMES = {0: "hover", 1: "attitude", 2: "helix", 3: "waypoints", 4: "offboard"}
SNAPSHOT_SIZE = 68


@jit
def _fill_snapshot(x, pp, ref, cout, v_cmd, estimated, att_est, onboard, out):
    """Every number of a RigSnapshot in one compiled call (layout: see LiveRig.snapshot)."""
    if estimated:
        phi = att_est[0]
        theta = att_est[1]
        psi = att_est[2]
        wx = att_est[3]
        wy = att_est[4]
        wz = att_est[5]
        for i in range(6):
            out[i] = onboard[i]
        quat_from_euler(phi, theta, psi, out[6:10])
    else:
        phi, theta, psi = euler_from_quat(x[6], x[7], x[8], x[9])
        wx = x[10]
        wy = x[11]
        wz = x[12]
        for i in range(10):
            out[i] = x[i]
    out[10] = phi
    out[11] = theta
    out[12] = psi
    dphi, dtheta, dpsi = euler_rates_from_body_rates(phi, theta, wx, wy, wz)
    out[13] = dphi
    out[14] = dtheta
    out[15] = dpsi
    out[16] = wx
    out[17] = wy
    out[18] = wz
    for i in range(3):
        out[19 + i] = ref[REF_POS + i]
        out[22 + i] = ref[REF_VEL + i]
        out[25 + i] = cout[OUT_ATT_DES + i]
        out[28 + i] = cout[OUT_ATT_RATE_DES + i]
        out[51 + i] = cout[OUT_S + i]
    for i in range(4):
        f = motor_thrust(x[13 + i], i, pp.k_v, pp.f_ceiling, pp.thrust_efficiency[i], pp.hw)
        out[31 + i] = f
        out[35 + i] = cout[OUT_THRUST_CMD + i]
        out[39 + i] = v_cmd[i]
        out[43 + i] = rotor_speed(f, pp.kf)
        out[47 + i] = cout[OUT_U + i]
    out[54] = cout[OUT_FLAGS]
    for i in range(13):
        out[55 + i] = x[i]


@dataclass(frozen=True)
class RigSnapshot:
    """The rig's state and decisions at one instant (SI, world ENU, body FRD)."""

    time_s: float
    armed: bool
    position: tuple
    velocity: tuple
    quaternion: tuple  # (w, x, y, z) of R_WB
    euler: tuple  # paper (phi, theta, psi)
    euler_rates: tuple
    body_rates: tuple  # omega_B
    position_target: tuple  # NaN in attitude mode
    velocity_target: tuple
    euler_target: tuple
    euler_rate_target: tuple
    thrusts: tuple  # N, from the motor state
    thrust_commands: tuple  # N
    voltage_commands: tuple  # V
    rotor_speeds: tuple  # rad/s
    u: tuple  # u1 (N), u2, u3, u4 (N m)
    sliding_surfaces: tuple
    flags: int
    guidance: str  # 'hover', 'attitude', 'helix', 'waypoints', 'offboard'
    waypoint_index: int
    mission_done: bool
    true_position: tuple = (math.nan,) * 3  # the physics, for SIM_STATE and tests
    true_velocity: tuple = (math.nan,) * 3
    true_quaternion: tuple = (1.0, 0.0, 0.0, 0.0)
    true_body_rates: tuple = (math.nan,) * 3
    sensors: "SensorSnapshot | None" = None  # None when the sensor models are off
    faults: "FaultStatus | None" = None  # injected faults, the supervisor's detections and failsafe
    #: simulated time in whole microseconds from the step counter; message time stamps use it
    #: (None: derive it from ``time_s``, rounded to the microsecond)
    time_us: int | None = None
    #: when the values were taken that are older than the snapshot: the control update whose motor
    #: commands ``voltage_commands`` are, and the load-cell sample ``thrusts`` and the sensor readings'
    #: cells come from (whole microseconds; None: the snapshot's own time)
    commands_time_us: int | None = None
    cells_time_us: int | None = None

    @property
    def stamp_us(self) -> int:
        """Simulated time in whole microseconds for message time stamps."""
        return self.time_us if self.time_us is not None else int(round(self.time_s * 1e6))

    @property
    def commands_stamp_us(self) -> int:
        """The stamp of the motor commands (SERVO_OUTPUT_RAW): the control update that computed them."""
        return self.commands_time_us if self.commands_time_us is not None else self.stamp_us

    @property
    def cells_stamp_us(self) -> int:
        """The stamp of the load-cell readings (HILMS_LOAD_CELLS): the sample they come from."""
        return self.cells_time_us if self.cells_time_us is not None else self.stamp_us

    @property
    def rotation(self) -> np.ndarray:
        """R_WB of the attitude the rig reports."""
        R = np.zeros((3, 3))
        quat_to_rot(*self.quaternion, R)
        return R

    @property
    def true_rotation(self) -> np.ndarray:
        R = np.zeros((3, 3))
        quat_to_rot(*self.true_quaternion, R)
        return R


class _Lazy:
    """A snapshot field computed on its first read from what :meth:`LiveRig.snapshot` captured
    (then kept: a non-data descriptor, the instance's own value takes over)."""

    def __init__(self, fn):
        self.fn = fn
        self.name = fn.__name__

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.fn(obj)
        return value


class _LiveSnapshot(RigSnapshot):
    """The snapshot :meth:`LiveRig.snapshot` returns: a :class:`RigSnapshot` whose sensor readings
    and fault status are built only when read (a served rig takes a snapshot every chunk
    and most chunks' messages read neither). What they are built from is copied when the snapshot
    is taken, so they are the values of that instant whenever they are read."""

    @_Lazy
    def sensors(self):
        captured = self.__dict__.pop("_sensors_src")
        return None if captured is None else _sensor_snapshot(*captured)

    @_Lazy
    def faults(self):
        return fault_status_of(*self.__dict__.pop("_faults_src"))


def _sensor_snapshot(imu_raw, si, combined, health, imu_modes, cell_raw, lcp, thrust_est, cell_modes):
    return SensorSnapshot(
        imu_raw=imu_raw,
        imu_si=si,
        fused=combined,
        imu_rejected_mask=int(health[0]),
        imu_fault_modes=tuple(map(int, imu_modes)),
        cell_raw=cell_raw,
        cell_grf=(lcp.newton_per_count * (cell_raw - lcp.zero_counts)) / GRAM_FORCE_N,
        cell_thrust_n=thrust_est,
        cell_rejected_mask=int(health[1]),
        cell_fault_modes=tuple(map(int, cell_modes)),
    )


@dataclass(frozen=True)
class SensorSnapshot:
    """The simulated sensors' latest readings and the estimators' view of their health."""

    imu_raw: np.ndarray  # (5, 9) raw counts: gyro, accel, mag per module
    imu_si: np.ndarray  # (5, 3, 3) calibrated SI [module, sensor (gyro, accel, mag), axis], FRD
    fused: np.ndarray  # (3, 3) ensemble of the modules [sensor, axis]
    imu_rejected_mask: int  # modules the ensemble rejects (bit m)
    imu_fault_modes: tuple  # injected fault per module (rig_emulator.sensors.faults codes)
    cell_raw: np.ndarray  # (4,) load-cell counts
    cell_grf: np.ndarray  # (4,) calibrated gram-force C (S - b)
    cell_thrust_n: np.ndarray  # (4,) guarded, filtered thrust the rig uses (N)
    cell_rejected_mask: int  # cells whose last reading a guard rejected
    cell_fault_modes: tuple


@dataclass(frozen=True)
class PowerStatus:
    """The bench supply (:meth:`LiveRig.power`)."""

    voltage_v: float
    current_a: float
    charge_c: float  # delivered since start
    energy_j: float


@dataclass(frozen=True)
class MissionStatus:
    """The mission guidance at one instant (:meth:`LiveRig.mission_status`)."""

    flying: bool  # the guidance follows the mission (not paused, not another target)
    index: int  # waypoint being flown to (the last one once done)
    done: bool  # the last waypoint was reached
    reached_t: np.ndarray  # time each waypoint was reached, NaN until then


@dataclass(frozen=True)
class SysidStatus:
    """The identification flight on a served rig (:meth:`LiveRig.sysid_status`)."""

    elapsed_s: float  # the programme's own time (s), 0 at its start
    part: str  # the part of guidance/sysid.py's table being flown ("after the programme" once done)
    done: bool  # the whole programme has been flown (it ended disarmed)
    stopped: str | None  # why it stopped itself before the end (None: it has not)
    replaced: bool = False  # it stopped because another guidance took over (which steers now)


class _ServedSysid(SysidProgramme):
    """The identification programme (guidance/sysid.py) on a served rig: its clock starts at the step it
    is started at, and it stops for good, touching nothing, when anything but itself disarms or arms the
    rig (the failsafe, a plug-in failure, a terminate action) or replaces its set-point (another guidance):
    it never takes the rig back from whatever took it."""

    def __init__(self, sim):
        super().__init__(sim, start_k=sim.k)
        self.armed_cmd = sim.armed  # the arming the programme last left the rig in
        self.stopped: str | None = None
        self.replaced = False

    def apply(self, sim) -> None:
        if self.stopped is not None:
            return
        if self.ofb is not None and (sim.gp.gtype != OFFBOARD or sim.gp.offboard is not self.ofb):
            self.stopped, self.replaced = "another guidance took over", True
            return
        if sim.armed != self.armed_cmd:
            self.stopped = "the rig was " + ("armed" if sim.armed else "disarmed") + " by something else"
            return
        super().apply(sim)
        self.armed_cmd = sim.armed


class LiveRig:
    """A rig that runs in chunks while commands arrive.

    Every command takes effect at the next :meth:`step`. Parameter changes are validated
    against the schema; a rejected change raises :class:`ConfigError` and leaves the rig
    exactly as it was.
    """

    def __init__(self, cfg: RigConfig, chunk_steps_max: int = 10_000, controller=None, external_motors: bool = False):
        """``controller``, ``external_motors``: see :class:`~rig_emulator.simulation.run.Simulation`."""
        self.sim = Simulation(cfg, log_capacity=chunk_steps_max + 1, controller=controller,
                              external_motors=external_motors)
        self._controller_arg = controller  # kept for reboot()
        self._external_motors = external_motors
        self.chunk_steps_max = chunk_steps_max
        self.sim.armed = False
        self._power_on()
        self._snap_values = np.zeros(SNAPSHOT_SIZE)
        self._fill = BoundEntry(_fill_snapshot)
        self._calibrations = 0
        self._mission = None  # (waypoints, radii, holds, speeds, free_xy) stored
        self._charge_c = 0.0  # charge the bench supply delivered since start (C), see power()
        self._energy_j = 0.0
        self._flying = None  # the same for the mission (or task path) the guidance was last started on
        self._path_kind = None  # what the waypoint guidance flies: "mission", "task" (fly_path) or None
        self._speed_override = None  # m/s set by change_speed (DO_CHANGE_SPEED) until a reboot

    # --- stepping ----------------------------------------------------------------------
    @property
    def cfg(self) -> RigConfig:
        return self.sim.cfg

    @property
    def time_s(self) -> float:
        return self.sim.time

    @property
    def dt(self) -> float:
        return self.sim.dt

    def step(self, n_steps: int) -> np.ndarray:
        """Advance ``n_steps`` physics steps; returns the log rows recorded meanwhile."""
        if n_steps > self.chunk_steps_max:
            raise ValueError(f"step({n_steps}): at most {self.chunk_steps_max} steps per call")
        sim = self.sim
        sim.log_row = 0
        sim.advance(n_steps)
        n_rows = sim.log_row
        rows = sim.log[:n_rows]
        if n_rows:  # the supply's charge and energy, integrated over the recorded rows
            cfg = sim.cfg
            thrusts, volts = rows[:, L.THRUST:L.THRUST + 4], rows[:, L.V_CMD:L.V_CMD + 4]
            supply_v = float(cfg["motors.voltage_max"])
            if n_rows <= SEQUENTIAL_SUM_MAX:  # a chunk's few rows: the same sum without numpy's call overhead
                amps = supply_current_sum(thrusts.tolist(), volts.tolist(), supply_v, cfg["airframe.km_over_kf"],
                                          cfg["motors.kv_rpm_per_v"])
            else:
                amps = float(np.sum(self._supply_current(thrusts, volts)))
            dt_log = sim.log_div * sim.dt
            self._charge_c += amps * dt_log
            self._energy_j += amps * dt_log * supply_v
        return rows

    def warm_up(self) -> float:
        return self.sim.warm_up()

    def _power_on(self) -> None:
        """The state of a hardware rig just switched on, disarmed: when its centre of gravity
        is off the joint (``joint.cog_offset``) it hangs still at its rest attitude
        (:func:`~rig_emulator.physics.hardware.rest_attitude`; the ``hilms`` airframe: about
        13 deg roll and pitch) with the initial yaw, its motors stopped: it has long since
        swung there on the bench. A rig with no hanging rest (``hilms-ideal``: any attitude is
        at rest) keeps the headless scenarios' initial state (``initial.euler_deg``, motors at
        the hover voltage), so a served flight started at t = 0 retraces the headless one."""
        self.sim.programme = None  # a served rig flies what its ground station commands, not the sysid programme
        sim = self.sim
        psi = math.radians(sim.cfg["initial.euler_deg"][2])
        rest = rest_attitude(sim.pp.hw, sim.pp.g, psi)
        if rest is None:
            return
        quat_from_euler(rest[0], rest[1], psi, sim.x[S.QUAT : S.QUAT + 4])
        sim.x[S.OMEGA : S.OMEGA + 3] = 0.0
        sim.x[S.MOTOR_V : S.MOTOR_V + 4] = 0.0
        sim.v_cmd[:] = 0.0
        sim.pp.hw.cmd_buf[:] = 0.0

    # --- observing -----------------------------------------------------------------------
    def snapshot(self) -> RigSnapshot:
        """What the rig reports (its own estimates when it flies on its sensors) and the truth.

        The sensor readings and the fault status are built when first read, from copies taken
        now (:class:`_LiveSnapshot`); the numbers come from one compiled call whose entry point
        is looked up once per set of argument objects (:class:`~rig_emulator.simulation.entry_points.BoundEntry`)."""
        sim = self.sim
        v = self._snap_values
        sp, ss = sim.sensing.params, sim.sensing.state
        args = (sim.x, sim.pp, sim.ref, sim.cout, sim.v_cmd, sp.estimated, ss.att_est, ss.onboard, v)
        self._fill(args, args)(*args)
        attitude_mode = sim.ref[REF_MODE] != 0.0  # attitude or rate mode: no position loop
        t = v.tolist()
        sensors_src = None
        if sp.simulate:
            st = ss.sstate
            sensors_src = (ss.imu_raw.copy(), ss.awork.si.copy(), ss.awork.combined.copy(), ss.health.tolist(),
                           st.imu_fault_mode.tolist(), ss.cell_raw.copy(), sp.lcp, ss.thrust_est.copy(),
                           st.cell_fault_mode.tolist())
        snap = object.__new__(_LiveSnapshot)
        nan3 = (math.nan,) * 3
        # the last control update and load-cell sample among the steps run (a step senses, controls,
        # then moves the physics: the snapshot after step k - 1 carries what those steps took)
        last = max(sim.k - 1, 0)
        rate = sim.cfg["sim.physics_rate_hz"]
        cells_us = last_update_us(last, sp.suite.cells.decim, rate) if sp.simulate else None
        snap.__dict__.update(
            time_s=float(sim.time),
            time_us=sim.time_us,
            commands_time_us=last_update_us(last, sim.ctrl_div, rate),
            cells_time_us=cells_us,
            armed=sim.armed,
            position=tuple(t[0:3]),
            velocity=tuple(t[3:6]),
            quaternion=tuple(t[6:10]),
            euler=tuple(t[10:13]),
            euler_rates=tuple(t[13:16]),
            body_rates=tuple(t[16:19]),
            position_target=nan3 if attitude_mode else tuple(t[19:22]),
            velocity_target=nan3 if attitude_mode else tuple(t[22:25]),
            euler_target=tuple(t[25:28]),
            euler_rate_target=tuple(t[28:31]),
            thrusts=tuple(t[31:35]),
            thrust_commands=tuple(t[35:39]),
            voltage_commands=tuple(t[39:43]),
            rotor_speeds=tuple(t[43:47]),
            u=tuple(t[47:51]),
            sliding_surfaces=tuple(t[51:54]),
            flags=int(t[54]),
            guidance=_GUIDANCE_NAMES[sim.gp.gtype],
            waypoint_index=int(sim.gstate[GS_INDEX]),
            mission_done=bool(sim.gstate[GS_DONE]),
            true_position=tuple(t[55:58]),
            true_velocity=tuple(t[58:61]),
            true_quaternion=tuple(t[61:65]),
            true_body_rates=tuple(t[65:68]),
            _sensors_src=sensors_src,
            _faults_src=fault_status_inputs(sim),
        )
        return snap

    @property
    def supply_voltage(self) -> float:
        """The bench supply's voltage (V): the motors' supply ceiling of Fig. 11 (a regulated lab supply)."""
        return float(self.cfg["motors.voltage_max"])

    def _supply_current(self, thrusts, voltages) -> np.ndarray:
        return supply_current(thrusts, voltages, self.supply_voltage, self.cfg["airframe.km_over_kf"],
                              self.cfg["motors.kv_rpm_per_v"])

    def power(self, snap: RigSnapshot | None = None) -> PowerStatus:
        """The bench supply now (:mod:`rig_emulator.physics.electrical`): voltage, the current the
        motor drivers draw at ``snap`` (default: now) and what was delivered since start."""
        snap = snap or self.snapshot()
        amps = float(self._supply_current(snap.thrusts, snap.voltage_commands)) if snap.armed else 0.0
        return PowerStatus(voltage_v=self.supply_voltage, current_a=amps, charge_c=self._charge_c,
                           energy_j=self._energy_j)

    def fault_status(self) -> FaultStatus:
        """Injected faults, the supervisor's detections and the failsafe, now (cheap: no snapshot)."""
        return self.sim.fault_status()

    def fault_signature(self) -> tuple:
        """Changes whenever :meth:`fault_status` or :attr:`plugin_failure` may have changed (cheap: for pollers)."""
        return len(self.sim.faults.events), self.sim.us.flags.tobytes(), id(self.sim.plugin_failure)

    def fault_events(self, since: int = 0) -> list[FaultEvent]:
        """Every fault injection (config or command) from number ``since`` on, oldest first."""
        return self.sim.faults.events[since:]

    def reached_times(self) -> np.ndarray:
        """Time each mission waypoint was reached (NaN until then)."""
        return self.sim.reached_t.copy()

    def mission_status(self) -> MissionStatus:
        """Where the mission guidance is (cheap: no snapshot)."""
        gs = self.sim.gstate
        return MissionStatus(flying=self.sim.gp.gtype == WAYPOINTS and gs[GS_STARTED] != 0.0
                             and self._path_kind == "mission",
                             index=int(gs[GS_INDEX]), done=bool(gs[GS_DONE]), reached_t=self.sim.reached_t.copy())

    @property
    def controller(self):
        """The controller plug-in flying (a :class:`rig_emulator.controllers.Controller`), or None."""
        return self.sim.plugin.controller

    @property
    def plugin_failure(self):
        """Why the plug-in stopped (a :class:`~rig_emulator.controllers.PluginError` naming it, the
        time and the problem; the rig then disarmed), None while it flies. Arming clears it."""
        return self.sim.plugin_failure

    def path_status(self) -> MissionStatus:
        """Where a path started with :meth:`fly_path` is (``flying`` False once anything else steers)."""
        gs = self.sim.gstate
        return MissionStatus(flying=self.sim.gp.gtype == WAYPOINTS and gs[GS_STARTED] != 0.0
                             and self._path_kind == "task",
                             index=int(gs[GS_INDEX]), done=bool(gs[GS_DONE]), reached_t=self.sim.reached_t.copy())

    @property
    def armed(self) -> bool:
        """Armed now (cheap: no snapshot)."""
        return self.sim.armed

    # --- commanding ------------------------------------------------------------------------
    def arm(self, armed: bool = True) -> None:
        self.sim.armed = bool(armed)

    # --- the identification flight (guidance/sysid.py) ------------------------------------------------
    def start_sysid(self) -> None:
        """Fly the identification flight from now, on the rig's own clock, exactly as the headless
        scenario ``sysid`` does from t = 0: the programme's attitude and thrust set-points, and its own
        disarming and re-arming for the swings (without the pre-arm checks: the rig swings then); it
        ends disarmed. ValueError when the rig is disarmed. It stops by itself when anything else arms,
        disarms or steers the rig (:class:`_ServedSysid`); :meth:`stop_sysid` stops it. Refused (ValueError)
        on a rig whose motors a flight stack in the loop drives (``external_motors``): the programme's
        set-points would steer nothing, and its disarming would cut the flight stack's motors."""
        if self._external_motors:
            raise ValueError("a flight stack in the loop drives the motors: fly the programme from it")
        if not self.sim.armed:
            raise ValueError("the rig is disarmed: arm it first")
        self.sim.programme = _ServedSysid(self.sim)

    def stop_sysid(self) -> None:
        """Forget the identification flight; the guidance and the arming stay as they are."""
        self.sim.programme = None

    def sysid_status(self) -> SysidStatus | None:
        """Where the identification flight is (None: none is being flown; cheap)."""
        prog = self.sim.programme
        if not isinstance(prog, _ServedSysid):
            return None
        t = prog.elapsed(self.sim)
        return SysidStatus(elapsed_s=t, part=part_of(t), done=t >= SYSID_DURATION_S, stopped=prog.stopped,
                           replaced=prog.replaced)

    def set_motor_voltages(self, volts) -> None:
        """Motor voltages 1-4 (V) from the next step on; a rig built with ``external_motors=True``."""
        self.sim.set_motor_voltages(volts)

    def set_motor_thrusts(self, thrusts) -> None:
        """Motor thrusts 1-4 (N, through Eq. 40) from the next step on; ``external_motors=True``."""
        self.sim.set_motor_thrusts(thrusts)

    def set_param(self, key: str, value) -> RigConfig:
        """Change one parameter of the running rig (validated; rejected changes change nothing)."""
        return self.set_params({key: value})

    def set_params(self, changes: dict) -> RigConfig:
        from rig_emulator.config.loader import fold_plugin_params

        changes = dict(fold_plugin_params(changes, self.cfg))  # controller.params.NAME -> controller.params
        for key in changes:
            if key in _RESTART_ONLY and changes[key] != self.cfg.get(key):
                raise ConfigError(f"{key}: cannot change while the rig runs; restart it with the new value")
        new_cfg = self.cfg.with_overrides(changes)
        # injected motor faults and the hardware effects' state (command buffer, noise) persist
        pp = physics_params(new_cfg, self.sim.pp.thrust_efficiency, self.sim.pp.hw)
        cp = control_params(new_cfg)
        up = self.sim.supervisor_params(new_cfg)
        gp = self._guidance_from(new_cfg, self.sim.gp)
        dist_keys = [k for k in changes if k.startswith("disturbance.")]
        dist = disturbances(new_cfg) if dist_keys else self.sim.dist
        plugin = self.sim.plugin
        if plugin.controller is not None and "controller.params" in changes:
            from rig_emulator.controllers import ControllerParams

            check = ControllerParams(type(plugin.controller).params, new_cfg["controller.params"], owner=plugin.name,
                                     info=plugin.controller.params.info)
        else:
            check = None  # (a PluginError above changed nothing)
        self.sim.cfg, self.sim.pp, self.sim.cp, self.sim.gp, self.sim.dist = new_cfg, pp, cp, gp, dist
        self.sim.up = up
        plugin.refresh_rig(cp)
        if check is not None:
            plugin.controller.params.array[:] = check.array
            plugin.controller.params.refresh()
        return new_cfg

    def _guidance_from(self, cfg: RigConfig, current):
        mission = self._flying if self._flying is not None else self._mission
        if mission is not None:
            gp = guidance_params(cfg, *mission)
        else:
            gp = guidance_params(cfg)
        # keep the live guidance choice (guided target, attitude target, mission) over the config's
        return gp._replace(gtype=current.gtype, hover_position=current.hover_position, att_offset=current.att_offset,
                           amplitude=current.amplitude, yaw=current.yaw, speed=self._cruise_speed(cfg),
                           offboard=current.offboard)

    def _cruise_speed(self, cfg: RigConfig) -> float:
        speed = cfg["guidance.speed"] if self._speed_override is None else self._speed_override
        return min(speed, cfg["guidance.max_speed"])  # PX4's MPC_XY_VEL_MAX caps DO_CHANGE_SPEED too

    def set_position_target(self, position, yaw: float | None = None) -> None:
        """Guided mode: hold the given world-ENU position (and yaw, rad) from the next step."""
        gp = self.sim.gp
        self.sim.gp = gp._replace(
            gtype=HOVER,
            hover_position=np.array(position, dtype=np.float64).reshape(3),
            yaw=gp.yaw if yaw is None else float(yaw),
        )

    def set_attitude_target(self, phi: float, theta: float, psi: float, thrust_fraction: float | None = None,
                            body_rates=None) -> None:
        """Attitude mode: hold the given paper Euler angles (rad); the position loop is off.

        With ``thrust_fraction`` (a fraction of :meth:`max_collective_thrust`) the collective
        thrust is the caller's instead of the hover thrust m g; ``body_rates`` (omega_B, FRD,
        rad/s) is a rate feed-forward, as Euler-angle rates at the target attitude. Either
        makes it an offboard set-point (guidance/offboard.py)."""
        if not all(math.isfinite(v) for v in (phi, theta, psi)):
            raise ValueError("attitude angles must be finite")
        gp = self.sim.gp
        euler_rates = None
        if body_rates is not None:
            w = np.asarray(body_rates, dtype=np.float64).reshape(3)
            if not np.all(np.isfinite(w)):
                raise ValueError("attitude rates must be finite")
            euler_rates = euler_rates_from_body_rates(phi, theta, w[0], w[1], w[2])
        if thrust_fraction is None and euler_rates is None:
            self.sim.gp = gp._replace(
                gtype=ATTITUDE, att_offset=np.array([phi, theta, 0.0]), amplitude=np.zeros(3), yaw=float(psi)
            )
            return
        ofb = self._offboard_array(OFB_KIND_ATTITUDE)
        ofb[OFB_ATT:OFB_ATT + 3] = (phi, theta, psi)
        rates = np.zeros(3) if euler_rates is None else np.asarray(euler_rates, dtype=np.float64).reshape(3)
        if not np.all(np.isfinite(rates)):
            raise ValueError("attitude rates must be finite")
        ofb[OFB_RATE:OFB_RATE + 3] = rates
        if thrust_fraction is not None:
            ofb[OFB_THRUST] = self.collective_thrust_from_fraction(thrust_fraction)
        self.sim.gp = gp._replace(gtype=OFFBOARD, offboard=ofb)

    # --- offboard set-points (guidance/offboard.py) -------------------------------------------
    def max_collective_thrust(self) -> float:
        """The largest collective thrust u1 the four motors give (N): 4 x the per-motor limit
        (thrust ceiling of Sec. 3-2 or Eq. 40 at the supply's full voltage, Fig. 11)."""
        return 4.0 * self.sim.cp.f_max

    def collective_thrust_from_fraction(self, fraction: float) -> float:
        """u1 (N) of a normalised collective thrust in [0, 1] (MAVLink's SET_ATTITUDE_TARGET.thrust
        reading: a fraction of the maximum); ValueError outside (the rig has no reverse thrust)."""
        if not (math.isfinite(fraction) and 0.0 <= fraction <= 1.0):
            raise ValueError(f"thrust {fraction:g} must be in [0, 1] (no reverse thrust)")
        return float(fraction) * self.max_collective_thrust()

    def hover_thrust_fraction(self) -> float:
        """The normalised collective thrust that carries the rig's weight, m g / u1_max."""
        return self.sim.cp.mass * self.sim.cp.g / self.max_collective_thrust()

    def _offboard_array(self, kind: float) -> np.ndarray:
        ofb = np.full(OFB_SIZE, np.nan)
        ofb[OFB_KIND] = kind
        ofb[OFB_T0] = self.sim.time
        return ofb

    def _current_heading(self) -> float:
        """psi to turn from or hold: the live offboard reference when one is flown, else the
        heading the controllers fly (:meth:`heading_now`)."""
        if self.sim.gp.gtype == OFFBOARD and self.sim.gp.offboard[OFB_KIND] == OFB_KIND_POSITION:
            return float(self.sim.ref[REF_YAW])
        return self.heading_now()

    def set_offboard_setpoint(self, position=None, velocity=None, acceleration=None,
                              yaw: float | None = None, yaw_rate: float | None = None) -> None:
        """Offboard position/velocity/acceleration set-point (world ENU, SI; NaN entries and
        ``None`` vectors are not controlled), heading ``yaw`` or turn rate ``yaw_rate`` (paper
        psi, rad and rad/s). Takes effect at the next step; replaces any other guidance."""
        ofb = self._offboard_array(OFB_KIND_POSITION)
        for start, vec in ((OFB_POS, position), (OFB_VEL, velocity), (OFB_ACC, acceleration)):
            if vec is not None:
                v = np.asarray(vec, dtype=np.float64).reshape(3)
                if np.any(np.isinf(v)):
                    raise ValueError("set-point values must be finite (NaN: not controlled)")
                ofb[start:start + 3] = v
        if np.all(np.isnan(ofb[OFB_POS:OFB_ACC + 3])):
            raise ValueError("a set-point needs a position, a velocity or an acceleration")
        for name, v in (("yaw", yaw), ("yaw rate", yaw_rate)):
            if v is not None and not math.isfinite(v):
                raise ValueError(f"{name} {v} is not a finite number")
        ofb[OFB_YAW] = np.nan if yaw is None else float(yaw)
        ofb[OFB_YAW_RATE] = np.nan if yaw_rate is None else float(yaw_rate)
        ofb[OFB_YAW0] = self._current_heading()
        ofb[OFB_POS0:OFB_POS0 + 3] = self._velocity_track_start(ofb)
        self.sim.gp = self.sim.gp._replace(gtype=OFFBOARD, offboard=ofb)

    def _velocity_track_start(self, ofb) -> np.ndarray:
        """OFB_POS0 of a new position-kind set-point: on each velocity-only axis, where the live
        set-point's velocity track stands now (a stream of velocity set-points carries one track on,
        as PX4's velocity integrator does), within VELOCITY_TRACK_LEAD_M of the vehicle; where no
        track is flown on that axis, the vehicle's position as its controllers fly it. NaN elsewhere."""
        start = np.full(3, np.nan)
        free = np.isnan(ofb[OFB_POS:OFB_POS + 3]) & ~np.isnan(ofb[OFB_VEL:OFB_VEL + 3])
        if not free.any():
            return start
        here = self.position_now()
        live = self.sim.gp.offboard
        flying = self.sim.gp.gtype == OFFBOARD and live[OFB_KIND] == OFB_KIND_POSITION
        for k in np.flatnonzero(free):
            track = math.nan
            if flying and math.isnan(live[OFB_POS + k]) and not math.isnan(live[OFB_VEL + k]):
                track = live[OFB_POS0 + k] + live[OFB_VEL + k] * (self.sim.time - live[OFB_T0])
            start[k] = here[k] if math.isnan(track) else min(max(track, here[k] - VELOCITY_TRACK_LEAD_M),
                                                               here[k] + VELOCITY_TRACK_LEAD_M)
        return start

    def set_body_rate_target(self, rates_frd, thrust_fraction: float | None = None) -> None:
        """Rate mode: track body rates (omega_B, FRD, rad/s) with a collective thrust (a fraction
        of :meth:`max_collective_thrust`; ``None``: hover thrust m g). The position loop is off."""
        r = np.asarray(rates_frd, dtype=np.float64).reshape(3)
        if not np.all(np.isfinite(r)):
            raise ValueError("body rates must be finite")
        ofb = self._offboard_array(OFB_KIND_RATES)
        ofb[OFB_RATE:OFB_RATE + 3] = r
        if thrust_fraction is not None:
            ofb[OFB_THRUST] = self.collective_thrust_from_fraction(thrust_fraction)
        self.sim.gp = self.sim.gp._replace(gtype=OFFBOARD, offboard=ofb)

    def set_collective_thrust(self, thrust_fraction: float) -> None:
        """Change only the collective thrust of the attitude or rate set-point being flown
        (a fraction of :meth:`max_collective_thrust`); ValueError when none is flown."""
        gp = self.sim.gp
        if gp.gtype != OFFBOARD or gp.offboard[OFB_KIND] == OFB_KIND_POSITION:
            raise ValueError("a thrust alone needs an attitude or body-rate set-point to go with")
        ofb = gp.offboard.copy()
        ofb[OFB_THRUST] = self.collective_thrust_from_fraction(thrust_fraction)
        self.sim.gp = gp._replace(offboard=ofb)

    def set_mission(self, waypoints, radii=None, holds=None, speeds=None, free_xy=None) -> None:
        """Store a waypoint mission (world ENU, m); :meth:`start_mission` flies it.

        Per waypoint (:func:`~rig_emulator.simulation.params.guidance_params`): switching
        radius (0 = ``guidance.switching_radius``), hold time (s), speed of the leg ending
        there (0 = ``guidance.speed``), ``free_xy`` (1 = X/Y where the rig is when the leg
        starts). A mission being flown keeps flying until :meth:`start_mission` replaces it.
        """
        wp = np.ascontiguousarray(waypoints, dtype=np.float64).reshape(-1, 3)
        if wp.shape[0] == 0:
            raise ValueError("a mission needs at least one waypoint")
        mission = (wp, radii, holds, speeds, free_xy)
        guidance_params(self.cfg, *mission)  # raises on inconsistent sizes, before anything changes
        self._mission = mission

    def start_mission(self, index: int = 0, keep_reached: bool = False) -> None:
        """Fly the stored mission from waypoint ``index`` (Sec. 4-4 switching), on a virtual
        line from where the rig is now. ``keep_reached`` keeps the reached times of a
        mission resumed after a pause (else they restart as NaN)."""
        if self._mission is None:
            raise ValueError("no mission stored")
        wp = self._mission[0]
        if not 0 <= index < wp.shape[0]:
            raise ValueError(f"mission index {index} out of range 0..{wp.shape[0] - 1}")
        gp = guidance_params(self.cfg, *self._mission)
        self.sim.gp = gp._replace(gtype=WAYPOINTS, yaw=self.sim.gp.yaw, speed=self._cruise_speed(self.cfg))
        self._flying = self._mission
        self._path_kind = "mission"
        if not (keep_reached and self.sim.reached_t.shape[0] == wp.shape[0]):
            self.sim.reached_t = np.full(wp.shape[0], np.nan)
        start_at(index, self.sim.time, self.position_now(), self.sim.gp, self.sim.gstate)

    def hold_position(self) -> None:
        """Hold where the vehicle is (:meth:`pose_now`: position and heading), e.g. a hold, a
        mission pause or a failsafe hold."""
        position, heading = self.pose_now()
        self.set_position_target(position, yaw=heading)

    def pose_now(self) -> tuple[np.ndarray, float]:
        """Where the vehicle is, as its controllers fly it: the position (world ENU, m) and the
        heading (paper psi, rad) of the onboard estimate with the sensor models on, else of the
        physics. Every set-point made from "where the vehicle is" (holds, take-off, landing,
        return, a mission's start, a set-point relative to the vehicle) starts from this, never
        from the physics state: the controllers close their loops on the estimate, so a target
        made from the truth is wherever the two have parted to (metres within a minute)."""
        sp, ss = self.sim.sensing.params, self.sim.sensing.state
        if sp.estimated:
            return ss.onboard[0:3].copy(), float(ss.att_est[2])
        x = self.sim.x
        return x[0:3].copy(), float(euler_from_quat(x[6], x[7], x[8], x[9])[2])

    def position_now(self) -> np.ndarray:
        """The position of :meth:`pose_now`, world ENU (m)."""
        return self.pose_now()[0]

    def heading_now(self) -> float:
        """The heading of :meth:`pose_now`, paper psi (rad)."""
        return self.pose_now()[1]

    def fly_path(self, waypoints, speeds=None, free_xy=None, holds=None) -> None:
        """Fly a guidance path (take-off, landing, return, fly-to) on Sec. 4-4 virtual lines
        from where the rig is now, without touching the stored mission; ``speeds`` per leg
        (0 = the cruise speed), ``free_xy`` 1 = the leg keeps the X/Y the rig has when it
        starts. Progress: :meth:`path_status`."""
        wp = np.ascontiguousarray(waypoints, dtype=np.float64).reshape(-1, 3)
        if wp.shape[0] == 0 or not np.all(np.isfinite(wp)):
            raise ValueError("a path needs at least one finite waypoint")
        path = (wp, None, holds, speeds, free_xy)
        gp = guidance_params(self.cfg, *path)
        self.sim.gp = gp._replace(gtype=WAYPOINTS, yaw=self.sim.gp.yaw, speed=self._cruise_speed(self.cfg))
        self._flying = path
        self._path_kind = "task"
        self.sim.reached_t = np.full(wp.shape[0], np.nan)
        start_at(0, self.sim.time, self.position_now(), self.sim.gp, self.sim.gstate)

    def change_speed(self, speed: float | None) -> None:
        """Cruise speed (m/s) of the waypoint legs from now on (the leg being flown restarts
        from here at that speed); ``None`` = back to ``guidance.speed``."""
        if speed is not None and not (0.0 < speed <= 100.0):
            raise ValueError(f"speed {speed:g} m/s must be in (0, 100]")
        self._speed_override = None if speed is None else float(speed)
        gp = self.sim.gp
        self.sim.gp = gp._replace(speed=self._cruise_speed(self.cfg))
        gs = self.sim.gstate
        if gp.gtype == WAYPOINTS and gs[GS_STARTED] != 0.0 and gs[GS_DONE] == 0.0 and gs[GS_HOLD_UNTIL] < 0.0:
            start_at(int(gs[GS_INDEX]), self.sim.time, self.position_now(), self.sim.gp, gs)

    def motor_test(self, motor: int, fraction: float, duration: float) -> float:
        """Bench motor test (DO_MOTOR_TEST): disarmed, command motor 1..4 to ``fraction`` of the
        full voltage for ``duration`` s from now (the others stay at 0 V); returns the voltage."""
        if self.sim.armed:
            raise ValueError("motor test needs the rig disarmed")
        if motor not in (1, 2, 3, 4) or not 0.0 <= fraction <= 1.0 or not 0.0 < duration <= 60.0:
            raise ValueError("motor 1..4, throttle in [0, 1], duration in (0, 60] s")
        volts = fraction * self.sim.pp.v_max
        cs = self.sim.cstate
        cs[CS_TEST_V : CS_TEST_V + 4] = 0.0
        cs[CS_TEST_V + motor - 1] = volts
        cs[CS_TEST_UNTIL] = self.sim.time + duration
        return volts

    def reboot(self) -> None:
        """Restart the simulation from the configuration's initial state (time 0, disarmed,
        faults and disturbances injected by command cleared), keeping the current parameters,
        the controller plug-in and the stored mission: what MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN
        does to a flight controller, without restarting the process. Like at power-on, the
        rig is disarmed with its motors stopped, hanging at rest (:meth:`_power_on`)."""
        cfg = self.sim.cfg
        self.sim = Simulation(cfg, log_capacity=self.chunk_steps_max + 1, controller=self._controller_arg,
                              external_motors=self._external_motors)
        self.sim.armed = False
        self._power_on()
        self.sim.warm_up()
        self._flying = None
        self._path_kind = None
        self._speed_override = None
        self.set_position_target(list(cfg["initial.position"]))

    def apply_shock(self, arm: int, torque: float, duration: float) -> None:
        """Fig. 12: a torque pulse on arm 1..4 starting now (positive pushes the tip down)."""
        if arm not in (1, 2, 3, 4):
            raise ValueError(f"arm {arm}: must be 1..4")
        if not (duration > 0.0 and math.isfinite(duration) and math.isfinite(torque)):
            raise ValueError("shock needs a finite torque and a positive duration")
        now = self.sim.time
        d = self.sim.dist
        keep = d.shocks[d.shocks[:, 0] + d.shocks[:, 3] > now] if d.shocks.size else d.shocks
        shocks = np.vstack([keep.reshape(-1, 4), [[now, float(arm), float(torque), float(duration)]]])
        self.sim.dist = d._replace(shocks=np.ascontiguousarray(shocks))

    def set_fault(self, device: str, index: int, mode: str, magnitude: float = 0.0) -> FaultEvent:
        """Inject (or with mode 'none' clear) a fault now: ``device`` 'imu' (module 0..4),
        'load_cell' or 'motor' (1..4, the arm number); see :mod:`rig_emulator.sensors.faults`.
        Raises ValueError with the reason and changes nothing when the fault is not possible."""
        return self.sim.set_fault(device, index, mode, magnitude)

    def _require_sensors(self) -> None:
        if not self.sim.sensing.params.simulate:
            raise ValueError("the sensor models are off (sensors.simulate = false)")

    def recalibrate(self) -> None:
        """Rerun the IMU calibration procedure (Sec. 4-1) and apply the new result.

        Reading: like the hardware's procedure it needs the rig still on the bench, so it is
        refused while armed; it uses a fresh random stream, so repeated calibrations differ
        as repeated procedures on the real rig would.
        """
        if self.sim.armed:
            raise ValueError("calibration needs the rig disarmed and still")
        self._require_sensors()
        self._calibrations += 1
        rng = np.random.default_rng(np.random.SeedSequence([self.cfg["sim.seed"], 0xCA1, self._calibrations]))
        self.sim.sensing.recalibrate_imu(self.cfg, rng)

    def set_extra_mass(self, arm: int, mass: float, distance: float) -> None:
        """Fig. 15: put (or with mass 0 remove) a point mass on arm 1..4 at ``distance`` from the joint."""
        if arm not in (1, 2, 3, 4):
            raise ValueError(f"arm {arm}: must be 1..4")
        if not (0.0 <= mass <= 10.0 and 0.0 <= distance <= 5.0):
            raise ValueError("extra mass must be in [0, 10] kg at a distance in [0, 5] m")
        self.sim.dist.extra[arm - 1, 0] = mass
        self.sim.dist.extra[arm - 1, 1] = distance
