"""Sensor messages: one builder per message, ``(snapshot, ctx) -> message(s)``.

Every value comes from :func:`rig_emulator.link.telemetry.ideal_sensors.sensor_readings` (through
``ctx.readings``), so these builders do not change when the simulated sensors replace
the ideal readings. Body axes are FRD in the rig and in MAVLink.
"""

from __future__ import annotations

from protocol.dialect import mavlink
from rig_emulator.link.telemetry import units as U

HIGHRES_FIELDS_IMU = 0x1FF  # x/y/z acc, gyro and mag updated (HIGHRES_IMU.fields_updated bits 0..8)
LOAD_CELL_NAMES = ("LC1_N", "LC2_N", "LC3_N", "LC4_N")  # NAMED_VALUE_FLOAT mirror: thrust per arm, N


def _scaled(cls, snap, ctx, module: int):
    r = ctx.readings(snap)
    # as Python floats (the same values): the unit conversions run in scalar math, not on numpy scalars
    a, g, m = r.accel[module].tolist(), r.gyro[module].tolist(), r.mag[module].tolist()
    return cls(
        time_boot_ms=U.time_boot_ms(snap.stamp_us),
        xacc=U.milli_g(a[0]), yacc=U.milli_g(a[1]), zacc=U.milli_g(a[2]),
        xgyro=U.milli_rad_s(g[0]), ygyro=U.milli_rad_s(g[1]), zgyro=U.milli_rad_s(g[2]),
        xmag=U.milli_gauss(m[0]), ymag=U.milli_gauss(m[1]), zmag=U.milli_gauss(m[2]), temperature=0)


def scaled_imu(snap, ctx):
    """IMU module 0."""
    return _scaled(mavlink.MAVLink_scaled_imu_message, snap, ctx, 0)


def scaled_imu2(snap, ctx):
    """IMU module 1."""
    return _scaled(mavlink.MAVLink_scaled_imu2_message, snap, ctx, 1)


def scaled_imu3(snap, ctx):
    """IMU module 2."""
    return _scaled(mavlink.MAVLink_scaled_imu3_message, snap, ctx, 2)


def highres_imu(snap, ctx):
    """The fused IMU reading (SI: m/s^2, rad/s, gauss)."""
    r = ctx.readings(snap)
    a, g, m = r.fused_accel.tolist(), r.fused_gyro.tolist(), r.fused_mag.tolist()
    return mavlink.MAVLink_highres_imu_message(
        time_usec=U.time_usec(snap.stamp_us), xacc=a[0], yacc=a[1], zacc=a[2],
        xgyro=g[0], ygyro=g[1], zgyro=g[2],
        xmag=U.gauss(m[0]), ymag=U.gauss(m[1]), zmag=U.gauss(m[2]),
        abs_pressure=0.0, diff_pressure=0.0, pressure_alt=0.0, temperature=0.0,
        fields_updated=HIGHRES_FIELDS_IMU, id=0)


def hilms_imu_module(snap, ctx):
    """One HILMS_IMU_MODULE per module, raw counts in the module's axes."""
    r = ctx.readings(snap)
    out = []
    t_us = U.time_usec(snap.stamp_us)
    count = U.raw_count_i16
    for i, raw in enumerate(r.imu_raw_counts.tolist()):
        out.append(mavlink.MAVLink_hilms_imu_module_message(
            time_usec=t_us, module_index=i,
            gyro_raw=[count(c) for c in raw[0:3]], accel_raw=[count(c) for c in raw[3:6]],
            mag_raw=[count(c) for c in raw[6:9]],
            fault=int(r.imu_faults[i])))
    return out


def _load_health(snap, readings) -> int:
    """Bit i: the cell of arm i + 1 is healthy (no injected fault, its readings not rejected by the guards)."""
    f = snap.faults
    if f is None or not f.cell_faults:
        return sum(1 << i for i, ok in enumerate(readings.load_healthy) if ok)
    return sum(1 << i for i, code in enumerate(f.cell_faults) if code == 0 and not (f.cells_flagged >> i) & 1)


def hilms_load_cells(snap, ctx):
    r = ctx.readings(snap)
    return mavlink.MAVLink_hilms_load_cells_message(
        time_usec=U.time_usec(snap.cells_stamp_us), raw_counts=[U.raw_count_u16(c) for c in r.load_raw_counts.tolist()],
        force_grf=r.load_force_grf.tolist(), thrust_n=r.load_thrust_n.tolist(),
        health=_load_health(snap, r))


def named_value_float(snap, ctx):
    """HILMS_LOAD_CELLS for stock ground stations: filtered thrust per arm (N) as LC1_N..LC4_N."""
    r = ctx.readings(snap)
    t = U.time_boot_ms(snap.cells_stamp_us)
    return [mavlink.MAVLink_named_value_float_message(time_boot_ms=t, name=name.encode("ascii"), value=float(f))
            for name, f in zip(LOAD_CELL_NAMES, r.load_thrust_n.tolist())]
