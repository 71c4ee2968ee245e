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
from rig_emulator.control.controller import OUT_ATT_DES, OUT_ATT_RATE_DES, OUT_FLAGS, OUT_S, OUT_THRUST_CMD, OUT_U, REF_MODE, REF_POS, REF_VEL
from rig_emulator.guidance.runner import ATTITUDE, GS_DONE, GS_INDEX, HOVER, WAYPOINTS, start_at
from rig_emulator.physics import state as S
from rig_emulator.physics.motors import rotor_speed, thrust_from_voltage
from rig_emulator.physics.rotation import euler_from_quat, euler_rates_from_body_rates, quat_to_rot
from rig_emulator.simulation.params import control_params, disturbances, guidance_params, physics_params
from rig_emulator.simulation.run import Simulation

# keys that fix array sizes or rates of a running rig
_RESTART_ONLY = ("sim.physics_rate_hz", "sim.control_rate_hz", "sim.log_rate_hz", "sim.seed")


def _floats(values) -> tuple:
    return tuple(float(v) for v in values)


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
    guidance: str  # 'hover', 'attitude', 'helix', 'waypoints'
    waypoint_index: int
    mission_done: bool

    @property
    def rotation(self) -> np.ndarray:
        R = np.zeros((3, 3))
        quat_to_rot(*self.quaternion, R)
        return R


class LiveRig:
    """A rig that runs in chunks while commands arrive.

    Every command takes effect at the next :meth:`step`. Parameter changes are validated
    against the schema; a rejected change raises :class:`ConfigError` and leaves the rig
    exactly as it was.
    """

    def __init__(self, cfg: RigConfig, chunk_steps_max: int = 10_000):
        self.sim = Simulation(cfg, log_capacity=chunk_steps_max + 1)
        self.chunk_steps_max = chunk_steps_max
        self.sim.armed = False
        self._mission = None  # (waypoints, radii, holds)

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
        self.sim.log_row = 0
        self.sim.advance(n_steps)
        return self.sim.log[: self.sim.log_row]

    def warm_up(self) -> float:
        return self.sim.warm_up()

    # --- observing -----------------------------------------------------------------------
    def snapshot(self) -> RigSnapshot:
        sim = self.sim
        x = sim.x
        phi, theta, psi = euler_from_quat(x[6], x[7], x[8], x[9])
        rates = euler_rates_from_body_rates(phi, theta, x[10], x[11], x[12])
        pp = sim.pp
        thrusts = tuple(thrust_from_voltage(v, pp.k_v, pp.f_ceiling) for v in x[S.MOTOR_V : S.MOTOR_V + 4])
        gname = {0: "hover", 1: "attitude", 2: "helix", 3: "waypoints"}[sim.gp.gtype]
        attitude_mode = sim.ref[REF_MODE] == 1.0
        return RigSnapshot(
            time_s=float(sim.time),
            armed=sim.armed,
            position=_floats(x[0:3]),
            velocity=_floats(x[3:6]),
            quaternion=_floats(x[6:10]),
            euler=(float(phi), float(theta), float(psi)),
            euler_rates=_floats(rates),
            body_rates=_floats(x[10:13]),
            position_target=(math.nan,) * 3 if attitude_mode else _floats(sim.ref[REF_POS : REF_POS + 3]),
            velocity_target=(math.nan,) * 3 if attitude_mode else _floats(sim.ref[REF_VEL : REF_VEL + 3]),
            euler_target=_floats(sim.cout[OUT_ATT_DES : OUT_ATT_DES + 3]),
            euler_rate_target=_floats(sim.cout[OUT_ATT_RATE_DES : OUT_ATT_RATE_DES + 3]),
            thrusts=_floats(thrusts),
            thrust_commands=_floats(sim.cout[OUT_THRUST_CMD : OUT_THRUST_CMD + 4]),
            voltage_commands=_floats(sim.v_cmd),
            rotor_speeds=_floats(rotor_speed(f, pp.kf) for f in thrusts),
            u=_floats(sim.cout[OUT_U : OUT_U + 4]),
            sliding_surfaces=_floats(sim.cout[OUT_S : OUT_S + 3]),
            flags=int(sim.cout[OUT_FLAGS]),
            guidance=gname,
            waypoint_index=int(sim.gstate[GS_INDEX]),
            mission_done=bool(sim.gstate[GS_DONE]),
        )

    def reached_times(self) -> np.ndarray:
        """Time each mission waypoint was reached (NaN until then)."""
        return self.sim.reached_t.copy()

    # --- commanding ------------------------------------------------------------------------
    def arm(self, armed: bool = True) -> None:
        self.sim.armed = bool(armed)

    def set_param(self, key: str, value) -> RigConfig:
        """Change one parameter of the running rig (validated; rejected changes change nothing)."""
        return self.set_params({key: value})

    def set_params(self, changes: dict) -> RigConfig:
        for key in changes:
            if key in _RESTART_ONLY and changes[key] != self.cfg.get(key):
                raise ConfigError(f"{key}: cannot change while the rig runs; restart it with the new value")
        new_cfg = self.cfg.with_overrides(changes)
        pp = physics_params(new_cfg)
        cp = control_params(new_cfg)
        gp = self._guidance_from(new_cfg, self.sim.gp)
        dist_keys = [k for k in changes if k.startswith("disturbance.")]
        dist = disturbances(new_cfg) if dist_keys else self.sim.dist
        self.sim.cfg, self.sim.pp, self.sim.cp, self.sim.gp, self.sim.dist = new_cfg, pp, cp, gp, dist
        return new_cfg

    def _guidance_from(self, cfg: RigConfig, current):
        if self._mission is not None:
            wp, radii, holds = self._mission
            gp = guidance_params(cfg, wp, radii, holds)
        else:
            gp = guidance_params(cfg)
        # keep the live guidance choice (guided target, attitude target, mission) over the config's
        return gp._replace(gtype=current.gtype, hover_position=current.hover_position, att_offset=current.att_offset,
                           amplitude=current.amplitude, yaw=current.yaw)

    def set_position_target(self, position, yaw: float | None = None) -> None:
        """Guided mode: hold the given world-ENU position (and yaw, rad) from the next step."""
        gp = self.sim.gp
        self.sim.gp = gp._replace(
            gtype=HOVER,
            hover_position=np.ascontiguousarray(position, dtype=np.float64),
            yaw=gp.yaw if yaw is None else float(yaw),
        )

    def set_attitude_target(self, phi: float, theta: float, psi: float) -> None:
        """Attitude mode: hold the given paper Euler angles (rad); the position loop is off."""
        gp = self.sim.gp
        self.sim.gp = gp._replace(
            gtype=ATTITUDE, att_offset=np.array([phi, theta, 0.0]), amplitude=np.zeros(3), yaw=float(psi)
        )

    def set_mission(self, waypoints, radii=None, holds=None) -> None:
        """Store a waypoint mission (world ENU, m); :meth:`start_mission` flies it."""
        wp = np.ascontiguousarray(waypoints, dtype=np.float64).reshape(-1, 3)
        if wp.shape[0] == 0:
            raise ValueError("a mission needs at least one waypoint")
        self._mission = (wp, radii, holds)

    def start_mission(self, index: int = 0) -> None:
        """Fly the stored mission from waypoint ``index`` (Sec. 4-4 switching)."""
        if self._mission is None:
            raise ValueError("no mission stored")
        wp, radii, holds = self._mission
        if not 0 <= index < wp.shape[0]:
            raise ValueError(f"mission index {index} out of range 0..{wp.shape[0] - 1}")
        gp = guidance_params(self.cfg, wp, radii, holds)
        self.sim.gp = gp._replace(gtype=WAYPOINTS, yaw=self.sim.gp.yaw)
        self.sim.reached_t = np.full(wp.shape[0], np.nan)
        start_at(index, self.sim.time, self.sim.x[0:3].copy(), self.sim.gp, self.sim.gstate)

    def hold_position(self) -> None:
        """Pause: hold the current position (e.g. a mission pause)."""
        self.set_position_target(self.sim.x[0:3].copy())

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

    def set_extra_mass(self, arm: int, mass: float, distance: float) -> None:
        """Fig. 15: put (or with mass 0 remove) a point mass on arm 1..4 at ``distance`` from the joint."""
        if arm not in (1, 2, 3, 4):
            raise ValueError(f"arm {arm}: must be 1..4")
        if not (0.0 <= mass <= 10.0 and 0.0 <= distance <= 5.0):
            raise ValueError("extra mass must be in [0, 10] kg at a distance in [0, 5] m")
        self.sim.dist.extra[arm - 1, 0] = mass
        self.sim.dist.extra[arm - 1, 1] = distance
