"""HIL messages built from a readout: fields, frames, units, flags (read back with pymavlink's
common dialect, as a flight stack decodes them)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import common

from protocol.frames import mavlink_euler_from_quaternion, quaternion_from_rotation, rwb_from_paper_euler
from protocol.geodesy import Home, TangentPlane, global_to_local_enu
from rig_emulator.link.px4_simulator import hil_messages, hil_units
from rig_emulator.link.px4_simulator.transport import TransportError, parse_spec
from rig_emulator.sensors.barometer import isa_pressure_temperature
from rig_emulator.simulation.hil_readout import HilReadout, sampled_between

HOME = Home(35.7, 51.4, 1200.0)
PLANE = TangentPlane(HOME)


def _readout(**kw) -> HilReadout:
    q = quaternion_from_rotation(rwb_from_paper_euler(0.1, -0.2, 0.3))
    p, t = isa_pressure_temperature(1200.0 + 2.0)
    base = dict(time_s=1.004, gyro=np.array([0.01, -0.02, 0.03]), accel=np.array([0.1, 0.2, -9.7]),
                mag=np.array([2.0e-5, 1.0e-5, 3.5e-5]), imu_sampled=True, mag_sampled=False,
                pressure_pa=p, temperature_c=t - 273.15, baro_altitude_m=1202.0,
                position=np.array([3.0, 4.0, 2.0]), velocity=np.array([0.5, -0.25, 1.0]),
                acceleration=np.array([0.0, 0.0, 1.0]), quaternion=q, body_rates=np.array([0.01, -0.02, 0.03]))
    base.update(kw)
    return HilReadout(**base)


def _roundtrip(msg):
    mav = common.MAVLink(None, srcSystem=1, srcComponent=1)
    (out,) = mav.parse_buffer(msg.pack(mav))
    return out


def test_hil_sensor_units_and_frames():
    r = _readout()
    m = _roundtrip(hil_messages.hil_sensor(r))
    assert m.get_type() == "HIL_SENSOR" and m.id == 0 and m.time_usec == 1004000
    assert (m.xacc, m.yacc) == pytest.approx((0.1, 0.2), abs=1e-6) and m.zacc == pytest.approx(-9.7, abs=1e-5)
    assert (m.xgyro, m.ygyro, m.zgyro) == pytest.approx((0.01, -0.02, 0.03), abs=1e-7)
    assert (m.xmag, m.ymag, m.zmag) == pytest.approx((0.2, 0.1, 0.35), abs=1e-6)  # gauss
    assert m.abs_pressure == pytest.approx(r.pressure_pa / 100.0, rel=1e-6)  # hPa
    assert m.pressure_alt == pytest.approx(1202.0, abs=1e-3) and m.diff_pressure == 0.0


@pytest.mark.parametrize("imu,mag,bits", [(True, False, 0x1A3F), (True, True, 0x1BFF), (False, True, 0x1BC0),
                                          (False, False, 0x1A00)])
def test_fields_updated_follow_the_samples(imu, mag, bits):
    assert hil_messages.fields_updated(_readout(imu_sampled=imu, mag_sampled=mag)) == bits
    assert bits & hil_units.FIELD_DIFF_PRESSURE == 0  # no airspeed sensor on the rig
    assert hil_messages.hil_sensor(_readout(imu_sampled=imu, mag_sampled=mag), all_fields=True).fields_updated == 0x1FFF


def test_hil_gps_is_the_virtual_position_about_home():
    r = _readout()
    m = _roundtrip(hil_messages.hil_gps(r, PLANE))
    enu = global_to_local_enu(HOME, m.lat * 1e-7, m.lon * 1e-7, m.alt * 1e-3)
    assert np.abs(enu - r.position).max() < 0.02  # degE7 is 1.1 cm
    assert (m.vn, m.ve, m.vd) == (-25, 50, -100)  # NED cm/s of ENU (0.5, -0.25, 1.0)
    assert m.fix_type == common.GPS_FIX_TYPE_3D_FIX and m.satellites_visible >= 6
    assert m.eph == 30 and m.epv == 30  # PX4 reads them as cm
    assert m.cog == round(math.degrees(math.atan2(50, -25)) * 100) % 36000
    assert m.time_usec == int((hil_messages.GPS_EPOCH_UNIX_S + 1.004) * 1e6)


def test_hil_state_quaternion_is_the_truth_in_ned():
    r = _readout()
    m = _roundtrip(hil_messages.hil_state_quaternion(r, PLANE))
    roll, pitch, yaw = mavlink_euler_from_quaternion(m.attitude_quaternion)
    assert (roll, pitch, yaw) == pytest.approx((0.1, 0.2, math.pi / 2 - 0.3), abs=1e-6)  # (phi, -theta, pi/2 - psi)
    assert (m.rollspeed, m.pitchspeed, m.yawspeed) == pytest.approx((0.01, -0.02, 0.03), abs=1e-7)
    assert (m.vx, m.vy, m.vz) == (-25, 50, -100)
    assert m.zacc == round(-1.0 / 9.80665 * 1000)  # 1 m/s^2 up = -102 mG NED
    assert abs(m.alt - 1202000) <= 1


def test_motor_voltage_mapping():
    assert hil_units.motor_voltage(0.5, 15.0) == 7.5
    assert hil_units.motor_voltage(1.5, 15.0) == 15.0 and hil_units.motor_voltage(-1.0, 15.0) == 0.0
    assert hil_units.motor_voltage(math.nan, 15.0) == 0.0
    assert hil_units.motor_voltage(math.inf, 15.0) == 0.0 and hil_units.motor_voltage(-math.inf, 15.0) == 0.0
    # the four motors of one message: only controls[0..3], each mapped as above
    controls = [0.25, 1.5, math.nan, -0.5, 0.9, 0.9] + [0.0] * 10
    assert hil_units.motor_voltages(controls, 12.0) == [3.0, 12.0, 0.0, 0.0]
    assert hil_units.motor_voltages(np.float32([0.1, 0.7, 1.0, 0.0]), 15.0) == [
        float(np.float32(0.1)) * 15.0, float(np.float32(0.7)) * 15.0, 15.0, 0.0]


def test_sampled_between():
    # the magnetometer samples at steps 0, 10, 20, ...; a lockstep step covers 4 physics steps
    assert [sampled_between(k, k + 4, 10) for k in range(0, 24, 4)] == [True, False, True, False, False, True]
    assert sampled_between(5, 5, 1) is False


@pytest.mark.parametrize("text,spec", [
    ("4560", ("tcp", "127.0.0.1", 4560)), ("0.0.0.0:4561", ("tcp", "0.0.0.0", 4561)),
    ("serial:/dev/ttyACM0", ("serial", "/dev/ttyACM0", 921600)), ("serial:/dev/ttyUSB1:57600", ("serial", "/dev/ttyUSB1", 57600)),
    ("/dev/pts/3:115200", ("serial", "/dev/pts/3", 115200)),
])
def test_parse_spec(text, spec):
    assert parse_spec(text) == spec


@pytest.mark.parametrize("text", ["", "x", "host:", "70000", ":4560", "serial:"])
def test_parse_spec_rejects(text):
    with pytest.raises(TransportError, match="--px4-simulator"):
        parse_spec(text)


@pytest.mark.parametrize("rate", [300.0, 2000.0, 0.0, -250.0])
def test_lockstep_rate_must_divide_the_physics_rate(rate):
    from types import SimpleNamespace

    from rig_emulator.config.loader import ConfigError
    from rig_emulator.simulation.lockstep import LockstepPlant

    rig = SimpleNamespace(cfg={"sim.physics_rate_hz": 1000.0}, dt=0.001)
    with pytest.raises(ConfigError, match="--px4-rate"):
        LockstepPlant(rig, rate, 1200.0)
    assert LockstepPlant(rig, 250.0, 1200.0).steps_per_update == 4


def _px4_fifo_counts(value: float, scale: float) -> int:
    """What PX4's simulator_mavlink makes of a HIL_SENSOR (id 0) accel/gyro value: float32
    divided by the FIFO scale, converted to int16 (truncation; beyond int16 it would wrap)."""
    counts = int(np.float32(value) / np.float32(scale))  # C's float -> integer truncates
    return counts


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_hil_sensor_saturates_at_the_range_px4_simulates(sign):
    """Seen with PX4 SITL (main, 2025-03): a touchdown at 0.7 m/s on the virtual ground stops
    the virtual vehicle within one step, about -185 m/s^2 on z; PX4's simulated IMU (int16
    FIFO, g/2048 per count = +-16 g) read it as +129 m/s^2 (wrapped round), its EKF2 took a
    downward kick and went 3 m below the ground. The message now saturates at full scale,
    as a real IMU does, and PX4 flags the sample clipped."""
    accel_scale = hil_units.PX4_ONE_G / 2048.0
    gyro_scale = math.radians(2000.0 / 32768.0)
    r = _readout(accel=np.array([0.3, sign * 200.0, sign * -185.0]), gyro=np.array([sign * 40.0, 0.02, -0.01]))
    m = _roundtrip(hil_messages.hil_sensor(r))
    assert m.xacc == pytest.approx(0.3, abs=1e-6) and m.ygyro == pytest.approx(0.02, abs=1e-7)  # in range: as is
    for value, scale in ((m.yacc, accel_scale), (m.zacc, accel_scale), (m.xgyro, gyro_scale)):
        counts = _px4_fifo_counts(value, scale)
        assert -32768 <= counts <= 32767  # no wrap round in PX4
        assert abs(counts) >= 32767 * 0.999  # PX4's clip limit: the sample is flagged as clipped
    assert math.copysign(1.0, m.zacc) == -sign and math.copysign(1.0, m.yacc) == sign  # the sign is kept
    assert m.zacc == pytest.approx(-sign * hil_units.ACCEL_LIMIT_M_S2, rel=1e-6)
    assert m.xgyro == pytest.approx(sign * hil_units.GYRO_LIMIT_RAD_S, rel=1e-6)
    assert abs(_px4_fifo_counts(m.zacc, accel_scale)) <= 32767 and hil_units.ACCEL_LIMIT_M_S2 / hil_units.PX4_ONE_G > 15.99


def test_hil_sensor_keeps_nan_and_in_range_values():
    r = _readout(accel=np.array([np.nan, 156.0, -156.0]))
    m = hil_messages.hil_sensor(r)
    assert math.isnan(m.xacc) and m.yacc == 156.0 and m.zacc == -156.0


def test_saturate_and_motor_voltages_are_the_min_max_expressions():
    # written as comparisons for speed: the same floats as min/max, NaN, +-inf and -0.0 included
    rng = np.random.default_rng(5)
    specials = [math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 2.0, -2.0, 0.5]
    values = specials + rng.normal(0.0, 2.0, 2000).tolist()
    for v in values:
        for limit in (1.0, 2.0, hil_units.ACCEL_LIMIT_M_S2):
            want = min(max(v, -limit), limit)
            got = hil_units.saturate(v, limit)
            assert (math.isnan(want) and math.isnan(got)) or (got == want and math.copysign(1, got) == math.copysign(1, want))
    for i in range(0, len(values) - 2, 3):
        got = hil_units.saturate_xyz(np.array(values[i:i + 3]), 2.0)
        want = [hil_units.saturate(v, 2.0) for v in values[i:i + 3]]
        assert [(g, math.copysign(1, g)) for g in got if not math.isnan(g)] == \
            [(w, math.copysign(1, w)) for w in want if not math.isnan(w)]
        assert [math.isnan(g) for g in got] == [math.isnan(w) for w in want]
    for i in range(0, len(values) - 3, 4):
        controls = values[i:i + 4]
        want = [min(max(c, 0.0), 1.0) * 15.0 if math.isfinite(c) else 0.0 for c in controls]
        got = hil_units.motor_voltages(controls, 15.0)
        assert [(g, math.copysign(1, g)) for g in got] == [(w, math.copysign(1, w)) for w in want]
