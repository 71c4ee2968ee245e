"""Units of the Simulator MAVLink API's messages: the one place this link scales numbers.

The generic SI -> MAVLink conversions (mm, cm/s, deg * 1e7, gauss, milli-g, microseconds)
are :mod:`rig_emulator.link.telemetry.units`; this module adds the few the HIL messages need
on top, and the actuator mapping (HIL_ACTUATOR_CONTROLS -> motor voltage).
"""

from __future__ import annotations

import math

PA_PER_HPA = 100.0
#: HIL_SENSOR.fields_updated bits (MAVLink common.xml HIL_SENSOR_UPDATED_FLAGS)
FIELDS_ACCEL = 0x007  # xacc, yacc, zacc
FIELDS_GYRO = 0x038  # xgyro, ygyro, zgyro
FIELDS_MAG = 0x1C0  # xmag, ymag, zmag
FIELD_ABS_PRESSURE = 0x200
FIELD_DIFF_PRESSURE = 0x400
FIELD_PRESSURE_ALT = 0x800
FIELD_TEMPERATURE = 0x1000
FIELDS_BARO = FIELD_ABS_PRESSURE | FIELD_PRESSURE_ALT | FIELD_TEMPERATURE
FIELDS_ALL = 0x1FFF
#: The full-scale range of the IMU PX4 makes of HIL_SENSOR id 0 (``simulator_mavlink``: a
#: simulated FIFO of int16 samples, accelerometer g/2048 per count = +-16 g, gyro
#: 2000/32768 deg/s per count = +-2000 deg/s). PX4 converts the float to int16 without a
#: bound, so a reading beyond it wraps round to the opposite sign (a touchdown's -18 g read
#: as +13 g). The limits are one count inside full scale: PX4 still flags the sample as
#: clipped (its limit is 0.999 of full scale) and its EKF2 then widens that axis's variance.
PX4_ONE_G = 9.80665  # CONSTANTS_ONE_G
ACCEL_LIMIT_M_S2 = 32767.0 * PX4_ONE_G / 2048.0  # 156.90 m/s^2
GYRO_LIMIT_RAD_S = math.radians(32767.0 * 2000.0 / 32768.0)  # 34.90 rad/s
#: HIL_ACTUATOR_CONTROLS.mode bits (MAV_MODE_FLAG) and .flags bits (HIL_ACTUATOR_CONTROLS_FLAGS)
MODE_FLAG_SAFETY_ARMED = 128
FLAG_LOCKSTEP = 1


def step_usec(t_s: float) -> int:
    """Simulated seconds (a whole number of physics steps, k dt) -> microseconds, rounded:
    consecutive 4 ms steps stay exactly 4000 us apart (truncating 0.007 s would give 6999)."""
    return int(round(t_s * 1e6))


def hpa(pressure_pa: float) -> float:
    """Pascal -> hectopascal (HIL_SENSOR.abs_pressure, diff_pressure)."""
    return pressure_pa / PA_PER_HPA


def saturate(value: float, limit: float) -> float:
    """``value`` clipped to +-``limit``, as a sensor at full scale reads (NaN stays NaN).
    ``min(max(value, -limit), limit)`` written as the comparisons those builtins make (the same
    float, NaN and -0.0 included, without two calls: six a flight-stack step)."""
    v = -limit if -limit > value else value  # max(value, -limit)
    return limit if limit < v else v  # min(v, limit)


def saturate_xyz(vector, limit: float) -> tuple:
    """:func:`saturate` of the three components of ``vector`` (as floats)."""
    x, y, z = map(float, vector)
    return saturate(x, limit), saturate(y, limit), saturate(z, limit)


def cm_u16(length_m: float) -> int:
    """Metres -> centimetres in a uint16 (HIL_GPS.eph/epv; 65535 = unknown)."""
    if not math.isfinite(length_m):
        return 65535
    return int(min(max(round(length_m * 100.0), 0), 65534))


def motor_voltage(control: float, voltage_max_v: float) -> float:
    """One HIL_ACTUATOR_CONTROLS.controls entry (a motor output, 0 = stopped, 1 = full) ->
    the motor driver's voltage command: ``control * voltage_max`` clipped to 0..voltage_max
    (Eq. 40 makes thrust linear in it: PX4's THR_MDL_FAC = 0). NaN stops the motor."""
    return motor_voltages((control,), voltage_max_v)[0]


def motor_voltages(controls, voltage_max_v: float) -> list:
    """:func:`motor_voltage` of ``controls[0..3]`` (HIL_ACTUATOR_CONTROLS.controls, motors 1-4),
    in one call: it runs at every flight-stack step."""
    isfinite = math.isfinite
    out = []
    for control in controls[0:4]:
        control = float(control)
        if isfinite(control):
            control = 0.0 if 0.0 > control else control  # min(max(control, 0.0), 1.0): the builtins' comparisons
            out.append((1.0 if 1.0 < control else control) * voltage_max_v)
        else:
            out.append(0.0)
    return out
