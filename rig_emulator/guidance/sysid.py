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
roll swing     55-66     hold phi 22 deg 3.5 s, thrust down to 0.3 of hover over     pendulum (CoG), friction;
                         1.5 s, disarmed 7.5 s                                       motor curve and bias
pitch swing    66-77     the same on theta, -22 deg                                  the same
yaw swing      77-90     level, thrust up from 0.3 over 1 s, psi ramp 60 deg/s 3 s   yaw friction; curve, bias
                         with the thrust down to 0.3, disarmed 7 s
=============  ========  ==========================================================  ==============================

90 s in all. The set-points are offboard attitude set-points (guidance/offboard.py) with their rate
feed-forward, updated every :data:`UPDATE_S`; disarmed, the motors get 0 V and the rig swings. The
programme only chooses set-points: the controllers, the sensors and the physics are the rig's own,
so a real rig flying the same programme (any ground station streaming these set-points) gives the
same kind of log.
"""

from __future__ import annotations

import math

import numpy as np

from rig_emulator.guidance.offboard import OFB_ATT, OFB_KIND, OFB_KIND_ATTITUDE, OFB_RATE, OFB_T0, OFB_THRUST

UPDATE_S = 0.01  # set-point period (s): 100 Hz, 50 updates per period of the fastest chirp
DURATION_S = 90.0
D2R = math.pi / 180.0

# (name, start s, end s): the parts of the table above
PARTS = (
    ("settle", 0.0, 3.0),
    ("roll chirp", 3.0, 17.0),
    ("pitch chirp", 17.0, 31.0),
    ("yaw chirp", 31.0, 43.0),
    ("thrust steps", 43.0, 55.0),
    ("roll swing", 55.0, 66.0),
    ("pitch swing", 66.0, 77.0),
    ("yaw swing", 77.0, 90.0),
)
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
    if 3.0 <= t < 17.0:
        att[0], rate[0] = _chirp(t - 3.0, 14.0, 0.15, 2.0, 6.0 * D2R, 0.6)
    elif 17.0 <= t < 31.0:
        att[1], rate[1] = _chirp(t - 17.0, 14.0, 0.15, 2.0, 6.0 * D2R, 0.6)
    elif 31.0 <= t < 43.0:
        att[2], rate[2] = _chirp(t - 31.0, 12.0, 0.1, 1.0, 20.0 * D2R, 0.3)
    elif 43.0 <= t < 55.0:
        k = min(int((t - 43.0) // 2.0), len(THRUST_STEPS) - 1)
        tk = (t - 43.0) - 2.0 * k
        prev = THRUST_STEPS[k - 1] if k > 0 else 1.0
        ramp = min(tk / THRUST_RAMP_S, 1.0)  # a cosine ramp: a step would trip the load cells' jump guard
        thrust = prev + (THRUST_STEPS[k] - prev) * (0.5 - 0.5 * math.cos(math.pi * ramp))
        if 0.5 <= tk < 1.0:
            att[k % 2] = 3.0 * D2R
        elif 1.0 <= tk < 1.5:
            att[k % 2] = -3.0 * D2R
    elif 55.0 <= t < 77.0:
        axis, t0 = (0, 55.0) if t < 66.0 else (1, 66.0)
        tk = t - t0
        if tk < SWING_HOLD_S:
            att[axis] = (22.0 if axis == 0 else -22.0) * D2R
            thrust = _low_thrust(tk, SWING_HOLD_S)
        else:
            armed = False
    elif 77.0 <= t < 90.0:
        tk = t - 77.0
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


def part_of(t: float) -> str:
    """The name of the programme's part at time ``t``."""
    for name, a, b in PARTS:
        if a <= t < b:
            return name
    return "after the programme"


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

    def elapsed(self, sim) -> float:
        """The programme's time at the simulation's current step (s)."""
        return (sim.k - self.start_k) * sim.dt

    def apply(self, sim) -> None:
        from rig_emulator.guidance.runner import OFFBOARD

        if self.ofb is not None and (sim.k - self.start_k) % self.period_steps:
            return  # between two update instants (a served rig's chunk starts there): the set-point stands
        armed, att, rate, thrust = setpoint(self.elapsed(sim))
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
