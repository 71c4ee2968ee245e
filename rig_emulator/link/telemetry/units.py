"""SI -> MAVLink field units: the one place where the link scales numbers.

Frames (ENU <-> NED, paper Euler <-> MAVLink attitude, local <-> global) are converted by
:mod:`protocol.frames` and :mod:`protocol.geodesy`; this module only changes units and
integer types, saturating at the field's range. A non-finite value becomes the field's
"unknown" marker where MAVLink defines one, otherwise 0 (never a cast of NaN).
"""

from __future__ import annotations

import math

G0 = 9.80665  # standard gravity, the MAVLink "milli-g" unit
GAUSS_PER_TESLA = 1e4
INT16 = (-32768, 32767)
INT32 = (-(2**31), 2**31 - 1)
INT16_MIN, INT16_MAX = INT16  # the bounds passed one by one: a call with *INT16 unpacks a tuple each time
INT32_MIN, INT32_MAX = INT32
UINT16_UNKNOWN = 65535


def clamp_int(value: float, lo: int, hi: int, unknown: int = 0) -> int:
    """``value`` rounded (half to even), saturated to ``lo..hi``; ``unknown`` for NaN and
    infinities (``round`` raises on them). Several calls per message at every step: no
    ``min``/``max`` calls."""
    try:
        v = int(round(value))
    except (ValueError, OverflowError):
        return unknown
    return lo if v < lo else (hi if v > hi else v)


def time_boot_ms(t_us: int) -> int:
    """Simulated time in whole microseconds (``RigSnapshot.stamp_us``, from the integer step
    counter) -> uint32 milliseconds since boot (wraps after 49.7 days). Integer division: a
    float clock's ``int(t * 1000)`` put some stamps 1 ms early (0.021 s * 1000 = 20.999...)."""
    return (int(t_us) // 1000) % 2**32


def time_usec(t_us: int) -> int:
    """Simulated time in whole microseconds -> uint64 microseconds since boot."""
    return int(t_us)


def time_usec_u32(t_us: int) -> int:
    """Simulated time in whole microseconds -> uint32 microseconds (SERVO_OUTPUT_RAW), wrapping."""
    return int(t_us) % 2**32


def time_ns(t_us: int) -> int:
    """Simulated time in whole microseconds -> nanoseconds (TIMESYNC)."""
    return int(t_us) * 1000


def unix_usec(t_unix_s: float) -> int:
    return int(t_unix_s * 1e6)


def deg_e7(deg: float) -> int:
    return clamp_int(deg * 1e7, INT32_MIN, INT32_MAX)


def mm(m: float) -> int:
    return clamp_int(m * 1000.0, INT32_MIN, INT32_MAX)


def cm_s_i16(v_m_s: float) -> int:
    return clamp_int(v_m_s * 100.0, INT16_MIN, INT16_MAX)


def cm_s_u16(v_m_s: float) -> int:
    return clamp_int(v_m_s * 100.0, 0, 65534, UINT16_UNKNOWN)


def heading_rad_to_cdeg(yaw_rad: float) -> int:
    """NED yaw (rad) -> heading in centidegrees 0..35999 (65535 when unknown)."""
    if not math.isfinite(yaw_rad):
        return UINT16_UNKNOWN
    return int(round(math.degrees(yaw_rad) * 100.0)) % 36000


def heading_rad_to_deg(yaw_rad: float) -> int:
    """NED yaw (rad) -> compass heading in whole degrees 0..359 (VFR_HUD)."""
    if not math.isfinite(yaw_rad):
        return 0
    return int(round(math.degrees(yaw_rad))) % 360


def milli_g(accel_m_s2: float) -> int:
    return clamp_int(accel_m_s2 / G0 * 1000.0, INT16_MIN, INT16_MAX)


def milli_rad_s(rate_rad_s: float) -> int:
    return clamp_int(rate_rad_s * 1000.0, INT16_MIN, INT16_MAX)


def milli_gauss(field_t: float) -> int:
    return clamp_int(field_t * GAUSS_PER_TESLA * 1000.0, INT16_MIN, INT16_MAX)


def gauss(field_t: float) -> float:
    return field_t * GAUSS_PER_TESLA


def pwm_us(voltage_v: float, voltage_max_v: float) -> int:
    """Motor voltage command 0..voltage_max -> a 1000..2000 us servo pulse."""
    if not math.isfinite(voltage_v) or voltage_max_v <= 0.0:
        return 1000
    return clamp_int(1000.0 + 1000.0 * min(max(voltage_v / voltage_max_v, 0.0), 1.0), 1000, 2000)


def percent(fraction: float) -> int:
    """A fraction 0..1 -> an integer percent 0..100."""
    return clamp_int(fraction * 100.0, 0, 100)


def raw_count_i16(counts: float) -> int:
    return clamp_int(counts, INT16_MIN, INT16_MAX)


def raw_count_u16(counts: float) -> int:
    return clamp_int(counts, 0, 65535)


def newton_to_grf(force_n: float) -> float:
    """Newton -> gram-force (standard gravity), the rig's load-cell unit."""
    return force_n / (G0 * 1e-3)
