"""A stand-in ArduPilot SITL on its JSON simulator interface (standard library only).

It plays what ArduPilot's ``libraries/SITL/SIM_JSON.cpp`` does, written from ArduPilot's
published sources and ``libraries/SITL/examples/JSON/readme.md``, not from the rig's code:

* send one servo packet per frame by UDP to the physics (port 9002): little-endian
  ``<HHI16H``, magic 18458, ``frame_rate``, ``frame_count`` (+1 per frame answered), 16 PWM
  values in microseconds (``<HHI32H``, magic 29569, with 32 channels);
* wait for the answer: newline-framed JSON lines, of which the last whole one counts,
  read as ``SIM_JSON`` reads it (:func:`parse_sensors`: ``strstr`` for each key, then ``atof``
  or ``sscanf("[%f, %f, %f]")`` right after ``"key":``; a missing required key rejects the
  line, so a space after a colon breaks the vectors as it does in ArduPilot);
* move its clock as SITL does (:class:`SitlClock`): by the change of ``timestamp`` when it
  is in (0, 0.1) s; a timestamp that goes back is a physics reset;
* re-send the same frame (same ``frame_count``) when no answer came (:meth:`JsonLink.resend`:
  ArduPilot does it after 1 s).

Its flight code is the PX4 stand-in's (:class:`gcs_tools.px4_peer.HoverController`: a PI rate
loop whose integral takes up the rig's centre of gravity off its joint, PID altitude, the
rig's plus-frame mixing), fed with the JSON's attitude, gyro, position and velocity; its
motors 1..4 go out on SERVO1..4, as ArduCopter's do with the rig's ``hilms.parm``.

``python -m gcs_tools.ardupilot_peer udp:127.0.0.1:9002 --duration 20`` flies a rig served
with ``rig-emulator serve --ardupilot-json`` and prints how well it held.
"""

from __future__ import annotations

import argparse
import math
import re
import socket
import struct
import sys
import time
from dataclasses import dataclass, field
from types import SimpleNamespace

from gcs_tools.px4_peer import HoverController

MAGIC_16, MAGIC_32 = 18458, 29569
DEFAULT_FRAME_RATE_HZ = 1200  # SIM_RATE_HZ's default
PWM_MIN, PWM_MAX = 1000, 2000

#: SIM_JSON.h keytable: (section, key, kind, required)
KEYTABLE = (
    ("", "timestamp", "double", True),
    ("imu", "gyro", "vector3", True),
    ("imu", "accel_body", "vector3", True),
    ("", "position", "vector3", True),
    ("", "attitude", "vector3", False),
    ("", "quaternion", "quaternion", False),
    ("", "velocity", "vector3", True),
    ("", "rng_1", "float", False),
    ("", "rng_2", "float", False),
    ("", "rng_3", "float", False),
    ("", "rng_4", "float", False),
    ("", "rng_5", "float", False),
    ("", "rng_6", "float", False),
    ("windvane", "direction", "float", False),
    ("windvane", "speed", "float", False),
    ("", "airspeed", "float", False),
    ("", "no_time_sync", "bool", False),
)
EULER_ATT, QUAT_ATT = 1 << 4, 1 << 5

# strtod's prefix: what atof and %f read (leading white space skipped)
_FLOAT = re.compile(r"\s*([+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan))", re.IGNORECASE)


def _atof(text: str, pos: int) -> float:
    m = _FLOAT.match(text, pos)
    return float(m.group(1)) if m else 0.0


def _sscanf_floats(text: str, pos: int, n: int) -> list | None:
    """``sscanf(p, "[%f, %f, %f]")`` (n values): '[' must be at ``pos``, each value is a
    strtod prefix, the ',' must follow it directly, white space after it is optional."""
    if not text.startswith("[", pos):
        return None
    pos += 1
    out = []
    for i in range(n):
        m = _FLOAT.match(text, pos)
        if not m:
            return None
        out.append(float(m.group(1)))
        pos = m.end()
        if i < n - 1:
            if not text.startswith(",", pos):
                return None
            pos += 1
            while pos < len(text) and text[pos].isspace():
                pos += 1
    return out


def parse_sensors(line: str) -> tuple[int, dict]:
    """SIM_JSON's ``parse_sensors`` of one line: (bitmask of the keys found, their values);
    the bitmask is 0 when a required key is missing."""
    mask, values = 0, {}
    for i, (section, key, kind, required) in enumerate(KEYTABLE):
        p = line.find(section)
        if p < 0:
            if required:
                return 0, values
            continue
        p += len(section) + 1
        p = line.find(key, p)
        if p < 0:
            if required:
                return 0, values
            continue
        mask |= 1 << i
        p += len(key) + 2
        name = f"{section}.{key}" if section else key
        if kind in ("double", "float"):
            values[name] = _atof(line, p)
        elif kind == "bool":
            values[name] = _atof(line, p) != 0.0
        else:
            v = _sscanf_floats(line, p, 4 if kind == "quaternion" else 3)
            if v is None:  # SIM_JSON prints "Failed to parse" and returns what it found so far
                return mask, values
            values[name] = v
    return mask, values


class SitlClock:
    """SITL's clock as ``SIM_JSON::recv_fdm`` moves it from the answers' ``timestamp``."""

    def __init__(self):
        self.last_timestamp_s = 0.0
        self.time_now_us = 0.0
        self.advances = 0  # frames that moved the clock (0 < delta < 0.1 s)
        self.resets = 0  # "Detected physics reset"

    def update(self, timestamp_s: float) -> float:
        if timestamp_s < self.last_timestamp_s:
            self.resets += 1
            delta = 0.0
        else:
            delta = timestamp_s - self.last_timestamp_s
        self.time_now_us += delta * 1e6
        if 0.0 < delta < 0.1:
            self.advances += 1
        self.last_timestamp_s = timestamp_s
        return delta


def servo_packet(frame_count: int, pwm, frame_rate_hz: int = DEFAULT_FRAME_RATE_HZ) -> bytes:
    pwm = [int(p) for p in pwm]
    if len(pwm) == 16:
        return struct.pack("<HHI16H", MAGIC_16, frame_rate_hz, frame_count, *pwm)
    return struct.pack("<HHI32H", MAGIC_32, frame_rate_hz, frame_count, *pwm)


class JsonLink:
    """The UDP socket ArduPilot talks to the physics with (from a port of its own)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 9002, timeout_s: float = 10.0, channels: int = 16):
        self.addr = (host, port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1" if host == "127.0.0.1" else "0.0.0.0", 0))
        self.sock.settimeout(timeout_s)
        self.channels = channels
        self.frame_count = 0
        self.frame_rate_hz = DEFAULT_FRAME_RATE_HZ
        self.clock = SitlClock()
        self.buffer = ""
        self.last_packet = b""
        self.lines: list[str] = []  # every whole line received (when recording)
        self.record = False

    def send(self, pwm) -> None:
        """The packet of the current frame."""
        pwm = list(pwm) + [PWM_MIN] * (self.channels - len(pwm))
        self.last_packet = servo_packet(self.frame_count, pwm, self.frame_rate_hz)
        self.sock.sendto(self.last_packet, self.addr)

    def resend(self) -> None:
        """The same packet again (same frame_count), as SITL after a second without an answer."""
        self.sock.sendto(self.last_packet, self.addr)

    def receive(self) -> tuple[str, dict]:
        """Wait for an answer; (its last whole line, the values parsed from it). As SIM_JSON
        it takes the text between the last two newlines of what it has; the frame is over."""
        while True:
            data = self.sock.recv(65536)
            self.buffer += data.decode("ascii")
            end = self.buffer.rfind("\n")
            start = self.buffer.rfind("\n", 0, end) if end > 0 else -1
            if start >= 0:
                break
        line = self.buffer[start + 1:end]
        self.buffer = self.buffer[end:]
        mask, values = parse_sensors(line)
        if not mask:
            raise ValueError(f"the physics' answer lacks a required field: {line!r}")
        if not mask & (EULER_ATT | QUAT_ATT):
            raise ValueError(f"the physics' answer has no attitude: {line!r}")
        if self.record:
            self.lines.append(line)
        self.clock.update(values["timestamp"])
        self.frame_count += 1
        return line, values

    def close(self) -> None:
        self.sock.close()


def euler_from_quaternion(q) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad, ZYX) of a body-to-NED quaternion [w, x, y, z]."""
    w, x, y, z = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


@dataclass
class JsonLog:
    """What the stand-in saw: (timestamp, roll, pitch, yaw, altitude up, climb) per frame."""

    states: list = field(default_factory=list)
    frames: int = 0
    wall_s: float = 0.0

    @property
    def sim_time_s(self) -> float:
        return self.states[-1][0] - self.states[0][0] if self.states else 0.0


def fly(link: JsonLink, duration_s: float, controller: HoverController | None = None,
        arm_at_s: float = 0.5) -> JsonLog:
    """Play ArduPilot for ``duration_s`` of the physics' time: a frame, its answer, the next
    frame with the motors the answer calls for (disarmed: 1000 us until ``arm_at_s``)."""
    controller = controller or HoverController()
    log = JsonLog()
    pwm = [PWM_MIN] * 4
    t0 = alt0 = None
    t_prev = None
    was_armed = False
    wall0 = time.perf_counter()
    while True:
        link.send(pwm)
        _, v = link.receive()
        log.frames += 1
        t = v["timestamp"]
        roll, pitch, yaw = euler_from_quaternion(v["quaternion"])
        pn, pe, pd = v["position"]
        if t0 is None:
            t0, alt0 = t, -pd
        alt, climb = -pd - alt0, -v["velocity"][2]
        log.states.append((t, roll, pitch, yaw, alt, climb))
        dt = 0.0 if t_prev is None else t - t_prev
        t_prev = t
        armed = t - t0 >= arm_at_s
        if armed and not was_armed:
            controller.arm()
        was_armed = armed
        if armed:
            controller.roll, controller.pitch, controller.yaw = roll, pitch, yaw
            controller.alt, controller.climb = alt, climb
            gx, gy, gz = v["imu.gyro"]
            motors = controller.motors(dt, SimpleNamespace(xgyro=gx, ygyro=gy, zgyro=gz))
            pwm = [PWM_MIN + (PWM_MAX - PWM_MIN) * u for u in motors]
        else:
            pwm = [PWM_MIN] * 4
        if t - t0 >= duration_s:
            break
    log.wall_s = time.perf_counter() - wall0
    return log


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m gcs_tools.ardupilot_peer", description=__doc__.split("\n")[0])
    p.add_argument("url", nargs="?", default="udp:127.0.0.1:9002", help="udp:HOST:PORT (default %(default)s)")
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds to fly (default %(default)s)")
    p.add_argument("--altitude", type=float, default=1.0, help="metres to climb and hold (default %(default)s)")
    args = p.parse_args(argv)
    kind, _, rest = args.url.partition(":")
    host, _, port = rest.rpartition(":")
    if kind != "udp" or not port.isdigit():
        p.error(f"{args.url!r}: expected udp:HOST:PORT")
    link = JsonLink(host, int(port))
    try:
        log = fly(link, args.duration, HoverController(altitude_m=args.altitude))
    except TimeoutError:
        print(f"no answer from the physics at {args.url} to frame {link.frame_count} within 10 s", file=sys.stderr)
        return 1
    finally:
        link.close()
    half = log.states[len(log.states) // 2:]
    print(f"{log.frames} frames, {log.sim_time_s:.2f} s simulated in {log.wall_s:.2f} s wall "
          f"({log.sim_time_s / max(log.wall_s, 1e-9):.1f}x real time)")
    alt = [s[4] for s in half]
    tilt = [math.degrees(math.acos(max(-1.0, min(1.0, math.cos(s[1]) * math.cos(s[2]))))) for s in half]
    print(f"altitude over the second half: mean {sum(alt) / len(alt):.3f} m, min {min(alt):.3f}, max {max(alt):.3f}")
    print(f"tilt over the second half: mean {sum(tilt) / len(tilt):.2f} deg, max {max(tilt):.2f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
