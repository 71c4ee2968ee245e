"""ArduPilot's JSON simulator interface, piece by piece: the servo packet, the motor map and the
answer line, read back with the stand-in's port of ArduPilot's own parser (SIM_JSON's
strstr/sscanf reading, which is stricter than JSON)."""

from __future__ import annotations

import json
import math
import random
import struct

import numpy as np
import pytest

from gcs_tools.ardupilot_peer import QUAT_ATT, SitlClock, parse_sensors, servo_packet as stand_in_packet
from protocol.frames import mavlink_quaternion_from_quat_wb
from rig_emulator.link.ardupilot_json import motor_map, servo_packet
from rig_emulator.link.ardupilot_json.state_json import state_line
from rig_emulator.simulation.hil_readout import HilReadout


def _readout(rng: random.Random, t: float = 0.25) -> HilReadout:
    v = lambda scale: tuple(rng.uniform(-scale, scale) for _ in range(3))  # noqa: E731
    q = [rng.gauss(0.0, 1.0) for _ in range(4)]
    n = math.sqrt(sum(c * c for c in q))
    return HilReadout(t, v(3.0), v(20.0), v(5e-5), True, True, 88000.0, 15.0, 1200.0, v(50.0), v(5.0), v(2.0),
                      tuple(c / n for c in q), v(3.0))


def test_servo_packets_as_arducopter_sends_them():
    rng = random.Random(7)
    for channels, magic in ((16, 18458), (32, 29569)):
        pwm = [rng.randrange(0, 65536) for _ in range(channels)]
        data = stand_in_packet(123456, pwm, 1200)  # the stand-in's own encoding (struct, from SIM_JSON.h)
        assert len(data) == 8 + 2 * channels and struct.unpack_from("<H", data)[0] == magic
        p = servo_packet.decode(data)
        assert (p.frame_rate_hz, p.frame_count, list(p.pwm_us)) == (1200, 123456, pwm)
        assert servo_packet.encode(1200, 123456, pwm) == data


@pytest.mark.parametrize("data,message", [
    (b"", "shorter than a servo packet"),
    (struct.pack("<HHI16H", 1234, 1200, 0, *[1000] * 16), "magic 1234"),
    (struct.pack("<HHI16H", 18458, 1200, 0, *[1000] * 16)[:-2], "a 16-channel packet is 40 bytes"),
    (struct.pack("<HHI16H", 29569, 1200, 0, *[1000] * 16), "a 32-channel packet is 72 bytes"),
])
def test_what_is_not_a_servo_packet_is_named(data, message):
    with pytest.raises(servo_packet.PacketError, match=message):
        servo_packet.decode(data)


def test_pwm_to_motor_voltage():
    assert motor_map.motor_voltages([1000, 1500, 2000, 1250] + [1900] * 12, 15.0) == [0.0, 7.5, 15.0, 3.75]
    # below the range (0: an output never set), above it: clipped
    assert motor_map.motor_voltages([0, 900, 2100, 65535], 15.0) == [0.0, 0.0, 15.0, 15.0]


def test_the_answer_is_read_back_by_ardupilots_parser():
    rng = random.Random(11)
    for _ in range(200):
        r = _readout(rng, t=rng.uniform(0.0, 1000.0))
        raw = state_line(r)
        text = raw.decode("ascii")
        assert text.startswith("\n{") and text.endswith("}\n") and text.count("\n") == 2
        assert '": ' not in text and ": " not in text  # compact: SIM_JSON's sscanf wants '[' right after ':'
        obj = json.loads(text)  # valid JSON too
        mask, values = parse_sensors(text.strip("\n"))
        assert mask & 0b1001111 == 0b1001111 and mask & QUAT_ATT, mask  # every required key, and the quaternion
        assert values["timestamp"] == r.time_s == obj["timestamp"]  # the same double, not a rounded one
        # what ArduPilot reads into floats: within a float's last place of the rig's double
        for got, sent in ((values["imu.gyro"], r.gyro), (values["imu.accel_body"], r.accel),
                          (values["quaternion"], mavlink_quaternion_from_quat_wb(r.quaternion))):
            assert all(abs(np.float32(g) - np.float32(s)) <= abs(np.spacing(np.float32(s))) for g, s in zip(got, sent))
        e, n, u = r.position
        assert obj["position"] == [n, e, -u]  # NED from home
        ve, vn, vu = r.velocity
        assert obj["velocity"] == pytest.approx([vn, ve, -vu], rel=1e-8, abs=1e-12)
        assert obj["position"] == values["position"]  # a double in ArduPilot: exact


def test_a_space_after_a_colon_would_break_ardupilots_parser():
    """What the stand-in's parser is for: ArduPilot reads the vector right after ``"key":``."""
    text = state_line(_readout(random.Random(3))).decode("ascii").strip("\n")
    assert parse_sensors(text)[0]
    spaced = json.dumps(json.loads(text))  # json.dumps' default separators put a space after ':'
    assert parse_sensors(spaced)[0] == 0 or "imu.gyro" not in parse_sensors(spaced)[1]


def test_a_diverged_plant_still_gives_a_line_ardupilot_reads():
    r = _readout(random.Random(5))._replace(gyro=(math.nan, math.inf, -math.inf))
    text = state_line(r).decode("ascii")
    assert '"gyro":[NaN,Infinity,-Infinity]' in text
    values = parse_sensors(text.strip("\n"))[1]
    g = values["imu.gyro"]
    assert math.isnan(g[0]) and g[1] == math.inf and g[2] == -math.inf


def test_sitl_clock():
    c = SitlClock()
    assert c.update(0.001) == pytest.approx(0.001) and c.advances == 1
    assert c.update(0.001) == 0.0 and c.advances == 1  # the same timestamp: SITL does not move
    c.update(0.5)
    assert c.advances == 1  # a jump of 0.1 s or more is not a step
    c.update(0.001)
    assert c.resets == 1  # back in time: a physics reset
