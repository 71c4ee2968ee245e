"""The identification flight (``guidance.type = "sysid"``, scenario ``sysid``): a fixed programme of
attitude and thrust set-points, and disarmed swings, that excites every effect the identification
estimates (``rig-gcs identify --tlog``, gcs_tools/identify/regression.py).

Built as ArduPilot's SystemId mode excites a vehicle (ArduCopter/mode_systemid.cpp): one axis at a
time, a chirp on the attitude set-point with a fade-in and fade-out, plus steps of the collective
thrust; and, for what the motors hide when they run (the joint's friction and the pendulum of the
centre of gravity), the rig is tilted and disarmed so that it swings freely on its joint.

=============  ========  ==========================================================  ==============================
part           time (s)  set-point                                                   what it excites
=============  ========  ==========================================================  ==============================
settle         0-3       level, hover thrust                                         hover point of each motor
roll chirp     3-17      phi 6 deg to 0.6 Hz, then 1/f^2, chirp 0.15-2 Hz             Ixx, roll friction, motors 2/4
pitch chirp    17-31     theta 6 deg, the same                                       Iyy, pitch friction, motors 1/3
yaw chirp      31-43     psi 20 deg to 0.3 Hz, then 1/f^2, chirp 0.1-1 Hz            Izz, yaw friction
thrust steps   43-55     u1 x (1.15, 0.8, 1.1, 0.7, 1.05, 1) of hover, 2 s each,       motor curve, gains, bias, delay
                         0.4 s ramps, roll/pitch doublets of 3 deg
hover          55-85     level, hover thrust                                         random torque
roll swing     85-96     hold phi 22 deg 3.5 s, thrust down to 0.3 of hover over     pendulum (CoG), friction;
                         1.5 s, disarmed 7.5 s                                       motor curve and bias
pitch swing    96-107    the same on theta, -22 deg                                  the same
yaw swing      107-120   level, thrust up from 0.3 over 1 s, psi ramp 60 deg/s 3 s   yaw friction; curve, bias
                         with the thrust down to 0.3, disarmed 7 s
=============  ========  ==========================================================  ==============================

120 s in all. The set-points are offboard attitude set-points (guidance/offboard.py) with their rate
feed-forward, updated every :data:`UPDATE_S`; disarmed, the motors get 0 V and the rig swings. The
random torque's level is a variance read from the armed rows, whose scatter falls as one over the root
of their length: the hover is there to lengthen them. Armed, a slow position hold (:func:`position_hold`) is added to the
set-points, from the rig's own virtual position and velocity (what LOCAL_POSITION_NED reports), so that
a rig unlike the preset does not drift out of its geofence. Otherwise the programme only chooses
set-points: the controllers, the sensors and the physics are the rig's own, so a real rig flying the
same programme (any ground station streaming these set-points) gives the same kind of log.
"""

from __future__ import annotations

import math

import numpy as np

from rig_emulator.guidance.offboard import OFB_ATT, OFB_KIND, OFB_KIND_ATTITUDE, OFB_RATE, OFB_T0, OFB_THRUST

UPDATE_S = 0.01  # set-point period (s): 100 Hz, 50 updates per period of the fastest chirp
D2R = math.pi / 180.0

# (name, length s): the parts of the table above, flown in this order
_LENGTHS = (
    ("settle", 3.0),
    ("roll chirp", 14.0),
    ("pitch chirp", 14.0),
    ("yaw chirp", 12.0),
    ("thrust steps", 12.0),
    ("hover", 30.0),
    ("roll swing", 11.0),
    ("pitch swing", 11.0),
    ("yaw swing", 13.0),
)
# (name, start s, end s)
PARTS = tuple((name, sum((n for _, n in _LENGTHS[:i]), 0.0), sum(n for _, n in _LENGTHS[:i + 1]))
              for i, (name, _) in enumerate(_LENGTHS))
DURATION_S = PARTS[-1][2]
THRUST_STEPS = (1.15, 0.8, 1.1, 0.7, 1.05, 1.0)  # kept below 1.2: near their ceiling the load cells read low
THRUST_RAMP_S = 0.4
SWING_HOLD_S = 3.5
LOW_THRUST = 0.3


def _chirp(t: float, duration: float, f0: float, f1: float, amplitude: float, knee: float, fade: float = 1.0):
    """Exponential chirp (ArduPilot's AP_Math/chirp.cpp shape) with cosine fades, its amplitude held up
    to ``knee`` Hz: (value, rate)."""
    if t < 0.0 or t > duration:
        return 0.0, 0.0
    b = math.log(f1 / f0) / duration
    phase = 2.0 * math.pi * f0 * (math.exp(b * t) - 1.0) / b
    freq = f0 * math.exp(b * t)
    w = 1.0
    dw = 0.0
    if t < fade:
        w = 0.5 - 0.5 * math.cos(math.pi * t / fade)
        dw = 0.5 * math.pi / fade * math.sin(math.pi * t / fade)
    elif t > duration - fade:
        s = duration - t
        w = 0.5 - 0.5 * math.cos(math.pi * s / fade)
        dw = -0.5 * math.pi / fade * math.sin(math.pi * s / fade)
    # above the knee the amplitude falls as 1 / f^2: a constant angular acceleration, which the motors
    # give without saturating and the load cells follow without tripping their jump guard
    k = 1.0 if freq <= knee else (knee / freq) ** 2
    dk = 0.0 if freq <= knee else -2.0 * k * b  # d k / dt (freq grows as exp(b t))
    v = amplitude * k * w * math.sin(phase)
    rate = amplitude * (k * dw * math.sin(phase) + dk * w * math.sin(phase)
                        + k * w * 2.0 * math.pi * freq * math.cos(phase))
    return v, rate


def _low_thrust(tk: float, hold: float) -> float:
    """Thrust (fraction of hover) of an armed stretch of ``hold`` s before a disarmed swing: up from
    :data:`LOW_THRUST` over 1 s after re-arming (no step for the load cells' jump guard), hover, then
    down to it over the last 1.5 s: the motors run over the whole lower curve, where the bias shows."""
    if tk < 1.0:
        return LOW_THRUST + (1.0 - LOW_THRUST) * tk
    if tk > hold - 1.5:
        return 1.0 - (1.0 - LOW_THRUST) * min((tk - (hold - 1.5)) / 1.5, 1.0)
    return 1.0


def setpoint(t: float):
    """The programme at time ``t`` (s): (armed, (phi, theta, psi) rad, Euler-rate feed-forward rad/s,
    collective thrust as a fraction of the hover thrust)."""
    att = [0.0, 0.0, 0.0]
    rate = [0.0, 0.0, 0.0]
    thrust = 1.0
    armed = True
    name, t0, t1 = _part(t)
    tk = t - t0
    if name == "roll chirp":
        att[0], rate[0] = _chirp(tk, t1 - t0, 0.15, 2.0, 6.0 * D2R, 0.6)
    elif name == "pitch chirp":
        att[1], rate[1] = _chirp(tk, t1 - t0, 0.15, 2.0, 6.0 * D2R, 0.6)
    elif name == "yaw chirp":
        att[2], rate[2] = _chirp(tk, t1 - t0, 0.1, 1.0, 20.0 * D2R, 0.3)
    elif name == "thrust steps":
        k = min(int(tk // 2.0), len(THRUST_STEPS) - 1)
        tk -= 2.0 * k
        prev = THRUST_STEPS[k - 1] if k > 0 else 1.0
        ramp = min(tk / THRUST_RAMP_S, 1.0)  # a cosine ramp: a step would trip the load cells' jump guard
        thrust = prev + (THRUST_STEPS[k] - prev) * (0.5 - 0.5 * math.cos(math.pi * ramp))
        if 0.5 <= tk < 1.0:
            att[k % 2] = 3.0 * D2R
        elif 1.0 <= tk < 1.5:
            att[k % 2] = -3.0 * D2R
    elif name in ("roll swing", "pitch swing"):
        axis = 0 if name == "roll swing" else 1
        if tk < SWING_HOLD_S:
            att[axis] = (22.0 if axis == 0 else -22.0) * D2R
            thrust = _low_thrust(tk, SWING_HOLD_S)
        else:
            armed = False
    elif name == "yaw swing":
        if tk < 6.0:
            thrust = _low_thrust(tk, 6.0)
        if 3.0 <= tk < 6.0:
            att[2] = 60.0 * D2R * (tk - 3.0)
            rate[2] = 60.0 * D2R
        elif tk >= 6.0:
            armed = False
    elif t >= DURATION_S:
        armed = False  # the programme ends disarmed, hanging on the joint
    return armed, att, rate, thrust


def _part(t: float):
    """The part flown at ``t``: (name, start s, end s); ``("", t, t)`` before or after the programme."""
    for part in PARTS:
        if part[1] <= t < part[2]:
            return part
    return "", t, t


HOLD_OMEGA = 0.4  # rad/s: the hold's natural frequency (critically damped), well below the chirps' 0.6-12 rad/s
HOLD_TILT_MAX = 4.0 * D2R  # the hold's largest tilt
HOLD_THRUST_MAX = 0.1  # the hold's largest change of the collective, as a fraction of the hover thrust


def position_hold(pos, vel, home, psi: float, g: float, vertical: bool):
    """The slow position hold flown on top of the programme (Eq. 33 and 35 for small angles): the
    virtual position ``pos`` and velocity ``vel`` (world ENU, the rig's own estimate, what
    LOCAL_POSITION_NED reports) pulled back to ``home`` by the critically damped acceleration
    ``a = -2 w v - w^2 (pos - home)``, ``w`` = :data:`HOLD_OMEGA`; horizontally as a tilt (at most
    :data:`HOLD_TILT_MAX`) towards ``a`` at yaw ``psi``, vertically (when ``vertical``) as a change of the
    collective (at most :data:`HOLD_THRUST_MAX` of hover). Returns (d phi, d theta, d thrust fraction).

    Why: the programme's set-points are open loop, and on a rig whose motors or centre of gravity differ
    from the preset's, a level hold tilts a little and the collective is a little off, so the virtual
    position runs away (hundreds of metres within the flight, out of any geofence, which then stops the
    programme). The hold keeps it within a few metres; its corrections are far slower and smaller than
    the programme's excitation, and the identification does not use the set-points anyway."""
    w = HOLD_OMEGA
    ax = -2.0 * w * vel[0] - w * w * (pos[0] - home[0])
    ay = -2.0 * w * vel[1] - w * w * (pos[1] - home[1])
    a_max = g * math.tan(HOLD_TILT_MAX)
    a_h = math.hypot(ax, ay)
    if a_h > a_max:
        ax *= a_max / a_h
        ay *= a_max / a_h
    c, s = math.cos(psi), math.sin(psi)
    dtheta = (ax * c + ay * s) / g
    dphi = (ax * s - ay * c) / g
    dthrust = 0.0
    if vertical:
        az = -2.0 * w * vel[2] - w * w * (pos[2] - home[2])
        dthrust = min(max(az / g, -HOLD_THRUST_MAX), HOLD_THRUST_MAX)
    return dphi, dtheta, dthrust


def part_of(t: float) -> str:
    """The name of the programme's part at time ``t``."""
    return _part(t)[0] or "after the programme"


def _virtual_state(sim):
    """The virtual position and velocity (world ENU) and yaw the rig's controllers use: its own estimate
    when it estimates (Eq. 1 from its sensors), else the true state."""
    if sim.sensing.params.estimated:
        ss = sim.sensing.state
        return ss.onboard[0:3], ss.onboard[3:6], float(ss.att_est[2])
    from rig_emulator.physics import state as S
    from rig_emulator.physics.rotation import euler_from_quat

    x = sim.x
    return x[S.POS:S.POS + 3], x[S.VEL:S.VEL + 3], float(euler_from_quat(*x[S.QUAT:S.QUAT + 4])[2])


class SysidProgramme:
    """Drives a :class:`~rig_emulator.simulation.run.Simulation` through the programme: before each
    piece of at most :data:`UPDATE_S` the set-point (and arming) of its start time is applied.

    The programme's clock starts at step ``start_k`` of the simulation (0: the headless scenario; a
    served rig starts it when commanded, :meth:`~rig_emulator.simulation.live.LiveRig.start_sysid`)."""

    def __init__(self, sim, start_k: int = 0):
        self.period_steps = max(1, int(round(UPDATE_S / sim.dt)))
        self.hover = sim.pp.mass * sim.pp.g
        self.start_k = int(start_k)
        self.ofb = None
        self.home = None  # the virtual position the hold keeps (world ENU): where the programme starts
        self.hold = (0.0, 0.0, 0.0)  # the hold's last correction: (d phi, d theta, d thrust fraction)

    def elapsed(self, sim) -> float:
        """The programme's time at the simulation's current step (s)."""
        return (sim.k - self.start_k) * sim.dt

    def apply(self, sim) -> None:
        from rig_emulator.guidance.runner import OFFBOARD

        if self.ofb is not None and (sim.k - self.start_k) % self.period_steps:
            return  # between two update instants (a served rig's chunk starts there): the set-point stands
        t = self.elapsed(sim)
        armed, att, rate, thrust = setpoint(t)
        pos, vel, psi = _virtual_state(sim)
        if self.home is None:
            self.home = pos.copy()
        # the hold leaves the thrust steps' collective alone: it would take back part of each step
        self.hold = (position_hold(pos, vel, self.home, psi, sim.pp.g, vertical=part_of(t) != "thrust steps")
                     if armed else (0.0, 0.0, 0.0))
        att = [att[0] + self.hold[0], att[1] + self.hold[1], att[2]]
        thrust += self.hold[2]
        if self.ofb is None or sim.gp.offboard is not self.ofb or sim.gp.gtype != OFFBOARD:
            ofb = np.full(sim.gp.offboard.shape[0], np.nan)
            ofb[OFB_KIND] = OFB_KIND_ATTITUDE
            ofb[OFB_T0] = sim.time
            sim.gp = sim.gp._replace(gtype=OFFBOARD, offboard=ofb)
            self.ofb = ofb
        ofb = self.ofb
        ofb[OFB_ATT:OFB_ATT + 3] = att
        ofb[OFB_RATE:OFB_RATE + 3] = rate
        ofb[OFB_THRUST] = thrust * self.hover
        if armed != sim.armed:
            sim.armed = armed

    def pieces(self, k: int, n_steps: int):
        """Split ``n_steps`` from step ``k`` at the programme's update instants: (steps) each."""
        end = k + n_steps
        k0, period = self.start_k, self.period_steps
        while k < end:
            nxt = k0 + ((k - k0) // period + 1) * period
            n = min(nxt, end) - k
            yield k, n
            k += n
