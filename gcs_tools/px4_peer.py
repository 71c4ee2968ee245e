"""A stand-in flight stack on PX4's Simulator MAVLink API (pymavlink, common dialect only).

It plays what PX4's ``simulator_mavlink`` module does, written from PX4's published
protocol (docs.px4.io "Simulation"; PX4-Autopilot
``src/modules/simulation/simulator_mavlink/SimulatorMavlink.cpp``), not from the rig's code:

* connect as a TCP client to the simulator (PX4: port 4560; retried until accepted), or
  talk over a serial line as a HITL board does;
* send ``COMMAND_LONG(MAV_CMD_SET_MESSAGE_INTERVAL, HIL_STATE_QUATERNION, 5000 us)`` and a
  HEARTBEAT, then wait: the clock is the ``time_usec`` of the HIL_SENSOR of ``id`` 0;
* answer every HIL_SENSOR of id 0 with one HIL_ACTUATOR_CONTROLS: ``controls[0..3]`` the
  motor outputs 0..1 (zeros while disarmed), ``mode`` MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
  (+ SAFETY_ARMED when armed), ``flags`` bit 0 = lockstep.

Its flight code is deliberately simple: a complementary filter (gyro + accelerometer) for
roll and pitch whose accelerometer is aided by the GPS velocity (the accelerometer of a
flying vehicle measures thrust, not tilt: only the kinematic acceleration the GPS sees,
taken out of it, leaves gravity; PX4's EKF2 fuses GPS velocity for the same reason), the
heading from gyro and magnetometer (to put that acceleration in body axes), the barometer's altitude, PX4's attitude structure (a P angle loop giving a
body-rate set-point, a PI rate loop whose integral, as PX4's ``MC_*RATE_I``, takes up a
steady torque such as the HILMS rig's centre of gravity off its joint) and PID altitude control,
and the motor mixing of the HILMS rig's plus frame as the rig documents it (motor 1 front,
2 right, 3 back, 4 left; 1 and 3 turn counter-clockwise seen from above). It takes off to
``altitude_m`` above the starting altitude and holds there.

``python -m gcs_tools.px4_peer tcp:127.0.0.1:4560 --duration 20`` flies a rig served with
``rig-emulator serve --px4-simulator 4560`` and prints how well it held.
"""

from __future__ import annotations

import argparse
import math
import os
import socket
import sys
import time
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import common as mavlink

HIL_STATE_QUATERNION_INTERVAL_US = 5000.0  # what PX4 asks for
MODE_CUSTOM = 1  # MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
MODE_ARMED = 128  # MAV_MODE_FLAG_SAFETY_ARMED
FLAG_LOCKSTEP = 1


@dataclass
class Airframe:
    """The rig as its documentation gives it (docs/how-to/flight-stacks.md): a plus frame."""

    mass_kg: float = 2.23
    inertia: tuple = (6.2e-2, 6.2e-2, 1.16e-1)
    arm_m: float = 0.28
    km_m: float = 0.016  # reaction moment per thrust
    max_thrust_n: float = 7.005  # per motor at control 1.0 (15 V x 47.62 gf/V)
    gravity: float = 9.81


@dataclass
class Gains:
    att_p: float = 2.0  # body-rate set-point per angle error (rad/s per rad), PX4's MC_ROLL_P
    rate_p: float = 8.0  # rad/s^2 per rad/s of rate error, PX4's MC_ROLLRATE_P (as angular acceleration)
    rate_i: float = 8.0  # rad/s^2 per rad of integrated rate error, PX4's MC_ROLLRATE_I
    rate_int_limit_nm: float = 0.5  # the most torque the integral may hold (N m), PX4's MC_RR_INT_LIM
    yaw_kd: float = 4.0
    alt_kp: float = 4.0  # m/s^2 per m
    alt_kd: float = 3.5
    alt_ki: float = 0.8
    filter_tau_s: float = 1.0  # complementary filter
    heading_tau_s: float = 5.0  # gyro + magnetometer heading
    climb_tau_s: float = 0.05  # low-pass of the barometric climb rate
    max_vertical_acc: float = 1.5  # m/s^2 (the rig's thrust-to-weight is 1.28)
    integrate_within_m: float = 0.2  # altitude error below which the integral acts


class HoverController:
    """Attitude + altitude hold on the HIL sensors (body FRD, NED)."""

    def __init__(self, frame: Airframe | None = None, gains: Gains | None = None, altitude_m: float = 1.0):
        self.frame = frame or Airframe()
        self.gains = gains or Gains()
        self.altitude_m = altitude_m
        self.roll = self.pitch = self.yaw = 0.0
        self.acc_ned = (0.0, 0.0, 0.0)  # kinematic acceleration from the GPS velocity (m/s^2, NED)
        self._gps_prev = None  # (t, vn, ve, vd)
        self.alt0 = None
        self.alt = self.climb = 0.0
        self.integral = 0.0
        self.rate_integral = [0.0, 0.0]  # roll, pitch (rad); reset on arming, as PX4 does
        self.t_prev = None

    def arm(self) -> None:
        """Forget the integrators (PX4 resets them while landed/disarmed)."""
        self.integral = 0.0
        self.rate_integral = [0.0, 0.0]

    def gps(self, msg) -> None:
        """One HIL_GPS (sent after the HIL_SENSOR of the same step): the kinematic acceleration
        from the change of its velocity since the previous one."""
        if self.t_prev is None:
            return
        v = (msg.vn * 0.01, msg.ve * 0.01, msg.vd * 0.01)
        if self._gps_prev is not None and self.t_prev > self._gps_prev[0]:
            dt = self.t_prev - self._gps_prev[0]
            self.acc_ned = tuple((v[i] - self._gps_prev[1 + i]) / dt for i in range(3))
        self._gps_prev = (self.t_prev, *v)

    def _body_from_ned(self, a):
        """NED vector ``a`` in body axes (FRD) at the estimated roll, pitch, heading (ZYX)."""
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        x1, y1 = cy * a[0] + sy * a[1], -sy * a[0] + cy * a[1]  # heading
        x2, z2 = cp * x1 - sp * a[2], sp * x1 + cp * a[2]  # pitch
        return x2, cr * y1 + sr * z2, -sr * y1 + cr * z2  # roll

    def _mag_heading(self, s) -> float:
        """Tilt-compensated magnetic heading (rad); the declination is not known here (as a bare compass)."""
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        xh = s.xmag * cp + (s.ymag * sr + s.zmag * cr) * sp
        yh = s.ymag * cr - s.zmag * sr
        return math.atan2(-yh, xh)

    def estimate(self, t: float, s) -> float:
        """Update the estimates from one HIL_SENSOR; returns the step (s)."""
        dt = 0.0 if self.t_prev is None else t - self.t_prev
        self.t_prev = t
        ab = self._body_from_ned(self.acc_ned)
        fx, fy, fz = s.xacc - ab[0], s.yacc - ab[1], s.zacc - ab[2]  # what gravity alone gives
        roll_acc = math.atan2(-fy, -fz)
        pitch_acc = math.atan2(fx, math.hypot(fy, fz))
        if self.alt0 is None:
            self.roll, self.pitch, self.alt0, self.alt = roll_acc, pitch_acc, s.pressure_alt, 0.0
            self.yaw = self._mag_heading(s)
            return dt
        a = dt / self.gains.filter_tau_s
        cr, sr, cp, tp = math.cos(self.roll), math.sin(self.roll), math.cos(self.pitch), math.tan(self.pitch)
        roll_dot = s.xgyro + (s.ygyro * sr + s.zgyro * cr) * tp
        pitch_dot = s.ygyro * cr - s.zgyro * sr
        yaw_dot = (s.ygyro * sr + s.zgyro * cr) / max(cp, 0.1)
        self.roll = (1.0 - a) * (self.roll + roll_dot * dt) + a * roll_acc
        self.pitch = (1.0 - a) * (self.pitch + pitch_dot * dt) + a * pitch_acc
        self.yaw += yaw_dot * dt
        err = (self._mag_heading(s) - self.yaw + math.pi) % (2.0 * math.pi) - math.pi
        self.yaw += dt / self.gains.heading_tau_s * err
        alt = s.pressure_alt - self.alt0
        if dt > 0.0:
            b = dt / (self.gains.climb_tau_s + dt)
            self.climb += b * ((alt - self.alt) / dt - self.climb)
        self.alt = alt
        return dt

    def motors(self, dt: float, s) -> list[float]:
        """Motor outputs 0..1 for motors 1..4."""
        f, g = self.frame, self.gains
        err = self.altitude_m - self.alt
        if abs(err) < g.integrate_within_m:  # no wind-up during the climb
            self.integral = min(max(self.integral + err * dt, -2.0), 2.0)
        acc = g.alt_kp * err - g.alt_kd * self.climb + g.alt_ki * self.integral
        acc = min(max(acc, -g.max_vertical_acc), g.max_vertical_acc)  # keep motor headroom for attitude
        tilt = max(math.cos(self.roll) * math.cos(self.pitch), 0.5)
        thrust = f.mass_kg * (f.gravity + acc) / tilt
        torque = []
        for axis, (angle, gyro) in enumerate(((self.roll, s.xgyro), (self.pitch, s.ygyro))):
            rate_err = -g.att_p * angle - gyro  # level: angle set-point 0
            j = f.inertia[axis]
            lim = g.rate_int_limit_nm / (j * g.rate_i)
            self.rate_integral[axis] = min(max(self.rate_integral[axis] + rate_err * dt, -lim), lim)
            torque.append(j * (g.rate_p * rate_err + g.rate_i * self.rate_integral[axis]))
        tx, ty = torque
        tz = f.inertia[2] * (-g.yaw_kd * s.zgyro)
        # plus frame, body FRD: roll = l (F4 - F2), pitch = l (F1 - F3), yaw = km (F1 - F2 + F3 - F4)
        c, l = thrust / 4.0, f.arm_m
        forces = (c + ty / (2 * l) + tz / (4 * f.km_m), c - tx / (2 * l) - tz / (4 * f.km_m),
                  c - ty / (2 * l) + tz / (4 * f.km_m), c + tx / (2 * l) - tz / (4 * f.km_m))
        return [min(max(fi / f.max_thrust_n, 0.0), 1.0) for fi in forces]


@dataclass
class PeerLog:
    """What the peer saw: every HIL_SENSOR (as tuples), the ground truth, counts."""

    sensors: list = field(default_factory=list)  # (time_usec, xacc, ..., fields_updated) when recorded
    truth: list = field(default_factory=list)  # (time_usec, q0..q3, alt_mm, vz_cm_s) when recorded
    steps: int = 0  # HIL_SENSOR of id 0 received (each answered)
    gps: int = 0
    first_usec: int = 0
    last_usec: int = 0
    wall_s: float = 0.0

    @property
    def sim_time_s(self) -> float:
        return (self.last_usec - self.first_usec) * 1e-6


class StreamLink:
    """A byte stream (a TCP socket or a serial file descriptor) with a MAVLink parser."""

    def __init__(self, send, recv, close, sysid: int = 1, compid: int = 1):
        self._send, self._recv, self._close = send, recv, close
        self.mav = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self.mav.robust_parsing = True

    @classmethod
    def tcp(cls, host: str, port: int, timeout_s: float = 10.0) -> "StreamLink":
        """Connect as PX4 does: retry until the simulator accepts."""
        deadline = time.monotonic() + timeout_s
        while True:
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            try:
                sock.connect((host, port))
                break
            except OSError:
                sock.close()
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.05)
        sock.settimeout(timeout_s)
        return cls(sock.sendall, lambda: sock.recv(65536), sock.close)

    @classmethod
    def fd(cls, fd: int, timeout_s: float = 10.0) -> "StreamLink":
        """A serial line (or a pseudo-terminal) as a file descriptor."""
        import select

        def recv() -> bytes:
            if not select.select([fd], [], [], timeout_s)[0]:
                raise TimeoutError("no data from the simulator")
            return os.read(fd, 65536)

        def send(data: bytes) -> None:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]

        return cls(send, recv, lambda: None)

    def send(self, msg) -> None:
        self._send(msg.pack(self.mav))

    def send_together(self, msgs) -> None:
        """Several messages in one write (they arrive together)."""
        self._send(b"".join(m.pack(self.mav) for m in msgs))

    def messages(self):
        """Decoded messages as they arrive (blocks; ends when the peer closes)."""
        while True:
            data = self._recv()
            if not data:
                return
            for msg in self.mav.parse_buffer(data) or ():
                yield msg

    def close(self) -> None:
        self._close()


def fly(link: StreamLink, duration_s: float, controller: HoverController | None = None, arm_at_s: float = 0.5,
        lockstep: bool = True, record: bool = True, answer_at_connect: bool = False) -> PeerLog:
    """Play the flight stack for ``duration_s`` of simulated time; returns what it saw.

    ``answer_at_connect``: a flight stack that is up when it connects sends its first
    HIL_ACTUATOR_CONTROLS (motors off, time 0) in the same write as its set-up messages, so
    that lockstep starts at t = 0 with no free run (PX4 answers only once its modules run)."""
    controller = controller or HoverController()
    log = PeerLog()
    flags = FLAG_LOCKSTEP if lockstep else 0
    setup = [mavlink.MAVLink_command_long_message(
                 0, 0, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                 mavlink.MAVLINK_MSG_ID_HIL_STATE_QUATERNION, HIL_STATE_QUATERNION_INTERVAL_US, 0, 0, 0, 0, 0),
             mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4, 0, 0, 0, 3)]
    if answer_at_connect:
        setup.append(mavlink.MAVLink_hil_actuator_controls_message(0, [0.0] * 16, MODE_CUSTOM, flags))
    link.send_together(setup)
    t0 = None
    was_armed = False
    wall0 = time.perf_counter()
    for msg in link.messages():
        kind = msg.get_type()
        if kind == "HIL_STATE_QUATERNION":
            if record:
                log.truth.append((msg.time_usec, *msg.attitude_quaternion, msg.alt, msg.vz))
            continue
        if kind == "HIL_GPS":
            log.gps += 1
            controller.gps(msg)
            continue
        if kind != "HIL_SENSOR" or msg.id != 0:
            continue
        if record:
            log.sensors.append((msg.time_usec, msg.xacc, msg.yacc, msg.zacc, msg.xgyro, msg.ygyro, msg.zgyro,
                                msg.xmag, msg.ymag, msg.zmag, msg.abs_pressure, msg.pressure_alt,
                                msg.temperature, msg.fields_updated))
        t = msg.time_usec * 1e-6
        if t0 is None:
            t0, log.first_usec = t, msg.time_usec
        log.last_usec = msg.time_usec
        log.steps += 1
        dt = controller.estimate(t, msg)
        armed = t - t0 >= arm_at_s
        if armed and not was_armed:
            controller.arm()
        was_armed = armed
        controls = controller.motors(dt, msg) if armed else [0.0] * 4
        link.send(mavlink.MAVLink_hil_actuator_controls_message(
            msg.time_usec, controls + [0.0] * 12, MODE_CUSTOM | (MODE_ARMED if armed else 0), flags))
        if t - t0 >= duration_s:
            break
    log.wall_s = time.perf_counter() - wall0
    return log


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m gcs_tools.px4_peer", description=__doc__.split("\n")[0])
    p.add_argument("url", nargs="?", default="tcp:127.0.0.1:4560", help="tcp:HOST:PORT (default %(default)s)")
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds to fly (default %(default)s)")
    p.add_argument("--altitude", type=float, default=1.0, help="metres to climb and hold (default %(default)s)")
    args = p.parse_args(argv)
    kind, _, rest = args.url.partition(":")
    host, _, port = rest.rpartition(":")
    if kind != "tcp" or not port.isdigit():
        p.error(f"{args.url!r}: expected tcp:HOST:PORT")
    link = StreamLink.tcp(host, int(port))
    try:
        log = fly(link, args.duration, HoverController(altitude_m=args.altitude))
    finally:
        link.close()
    alt = [(row[5] - log.truth[0][5]) / 1000.0 for row in log.truth[len(log.truth) // 2:]] if log.truth else []
    print(f"{log.steps} sensor steps, {log.sim_time_s:.2f} s simulated in {log.wall_s:.2f} s wall "
          f"({log.sim_time_s / max(log.wall_s, 1e-9):.1f}x real time)")
    if alt:
        print(f"altitude over the second half: mean {sum(alt) / len(alt):.3f} m, min {min(alt):.3f}, max {max(alt):.3f}")
        # tilt: the angle between body z and down, from the true quaternion (cos = 1 - 2 (x^2 + y^2))
        tilt = [math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (r[2] ** 2 + r[3] ** 2)))))
                for r in log.truth[len(log.truth) // 2:]]
        print(f"tilt over the second half: mean {sum(tilt) / len(tilt):.2f} deg, max {max(tilt):.2f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
