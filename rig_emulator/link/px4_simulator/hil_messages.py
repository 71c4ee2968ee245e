"""The simulator's messages to the flight stack: one builder per message, from a
:class:`~rig_emulator.simulation.hil_readout.HilReadout`.

Frames: HIL_SENSOR's vectors are body FRD, which is the rig's body frame B, so they pass
unchanged; positions and velocities are NED (``protocol.frames``) and geodetic about
``home`` (``protocol.geodesy.TangentPlane``); the attitude quaternion is R_NED_FRD. Units: HIL_SENSOR
m/s^2, rad/s, gauss, hPa, m, degC; HIL_GPS and HIL_STATE_QUATERNION degE7, mm, cm/s,
centidegrees, milli-g (:mod:`rig_emulator.link.telemetry.units`,
:mod:`rig_emulator.link.px4_simulator.hil_units`).
"""

from __future__ import annotations

import math

from protocol.dialect import mavlink
from protocol.frames import enu_to_ned_xyz, mavlink_quaternion_from_quat_wb
from protocol.geodesy import TangentPlane
from rig_emulator.link.telemetry import units as U
from rig_emulator.link.px4_simulator import hil_units as H

#: the virtual GPS (ideal, as the rig's GPS_RAW_INT): 3D fix, 10 satellites, 0.3 m accuracy
GPS_SATELLITES = 10
GPS_ACCURACY_M = 0.3
GPS_SPEED_UNKNOWN_BELOW_M_S = 0.01  # course over ground reported unknown below this speed
#: HIL_GPS.time_usec is UTC (PX4 copies it to sensor_gps.time_utc_usec). Reading: simulated
#: time from a fixed epoch, so that runs stay bit-identical: 2024-07-01T00:00:00Z.
GPS_EPOCH_UNIX_S = 1719792000.0
GPS_EPOCH_USEC = int(GPS_EPOCH_UNIX_S) * 1_000_000


def fields_updated(readout) -> int:
    """HIL_SENSOR.fields_updated: the accelerometer and gyro bits when the IMU modules took
    a sample during the step, the magnetometer bits when the magnetometers did, and the
    barometer bits (absolute pressure, pressure altitude, temperature) every step. The rig
    has no airspeed sensor: the differential-pressure bit is never set."""
    bits = H.FIELDS_BARO
    if readout.imu_sampled:
        bits |= H.FIELDS_ACCEL | H.FIELDS_GYRO
    if readout.mag_sampled:
        bits |= H.FIELDS_MAG
    return bits


#: HIL_SENSOR.abs_pressure alternates by this much about the ideal (ISA) pressure, one sign
#: per step (about 1 mm of altitude). Reading: the virtual barometer has no noise, and PX4
#: flags a barometer whose reading repeats exactly 100 times in a row as failed (its
#: DataValidator's STALE check, 0.4 s at 250 Hz); seen with PX4 SITL in a steady hover:
#: "BARO #0 failed: STALE!" and a switch to the second barometer, which failed alike.
#: ``pressure_alt`` (which PX4 does not read) stays the ideal altitude.
BARO_DITHER_PA = 0.01


def hil_sensor(readout, sensor_id: int = 0, all_fields: bool = False, pressure_dither_pa: float = 0.0):
    """HIL_SENSOR: the IMU modules' ensemble, the magnetometers' and the virtual barometer.
    ``all_fields`` flags every field (0x1FFF) whatever was sampled, as jMAVSim does.

    The accelerometer and gyro saturate at the range of the IMU PX4 makes of them
    (:data:`~rig_emulator.link.px4_simulator.hil_units.ACCEL_LIMIT_M_S2`, +-16 g, and
    ``GYRO_LIMIT_RAD_S``, +-2000 deg/s), as a real IMU at full scale: beyond it PX4 would
    wrap the reading round to the opposite sign. The virtual ground stops a touchdown in one
    physics step, so a landing at 0.7 m/s reads about -18 g for one 4 ms step.
    ``pressure_dither_pa`` is added to ``abs_pressure`` (the session alternates its sign:
    :data:`BARO_DITHER_PA`).

    It runs at every flight-stack step: positional fields (the keyword form costs pymavlink's
    constructor a dictionary per message), the units from their one place (``hil_units``,
    ``units``)."""
    a, g, m = readout.accel, readout.gyro, readout.mag
    gauss = U.gauss
    return mavlink.MAVLink_hil_sensor_message(
        H.step_usec(readout.time_s),  # time_usec
        *H.saturate_xyz(a, H.ACCEL_LIMIT_M_S2),  # xacc, yacc, zacc
        *H.saturate_xyz(g, H.GYRO_LIMIT_RAD_S),  # xgyro, ygyro, zgyro
        gauss(float(m[0])), gauss(float(m[1])), gauss(float(m[2])),  # xmag..zmag
        H.hpa(readout.pressure_pa + pressure_dither_pa),  # abs_pressure
        0.0,  # diff_pressure
        float(readout.baro_altitude_m),  # pressure_alt
        float(readout.temperature_c),  # temperature
        H.FIELDS_ALL if all_fields else fields_updated(readout),
        sensor_id)


def geodetic(readout, plane: TangentPlane) -> tuple:
    """(lat_deg, lon_deg, alt_m) of the readout's virtual position about the home of ``plane``
    (computed once per step when HIL_GPS and HIL_STATE_QUATERNION both go)."""
    e, n, u = readout.position
    return plane.to_global(float(e), float(n), float(u))


def hil_gps(readout, plane: TangentPlane, geo: tuple | None = None):
    """HIL_GPS: the virtual position about the home of ``plane`` (3D fix, ideal); ``geo``:
    :func:`geodetic` of the readout if already computed."""
    lat, lon, alt = geo or geodetic(readout, plane)
    vn, ve, vd = enu_to_ned_xyz(*readout.velocity)
    speed = math.hypot(vn, ve)
    cog = U.heading_rad_to_cdeg(math.atan2(ve, vn)) if speed >= GPS_SPEED_UNKNOWN_BELOW_M_S else U.UINT16_UNKNOWN
    accuracy_cm = H.cm_u16(GPS_ACCURACY_M)
    return mavlink.MAVLink_hil_gps_message(
        time_usec=GPS_EPOCH_USEC + H.step_usec(readout.time_s), fix_type=mavlink.GPS_FIX_TYPE_3D_FIX,
        lat=U.deg_e7(lat), lon=U.deg_e7(lon), alt=U.mm(alt), eph=accuracy_cm, epv=accuracy_cm,
        vel=U.cm_s_u16(speed), vn=U.cm_s_i16(vn), ve=U.cm_s_i16(ve), vd=U.cm_s_i16(vd), cog=cog,
        satellites_visible=GPS_SATELLITES, id=0, yaw=0)


def hil_state_quaternion(readout, plane: TangentPlane, geo: tuple | None = None):
    """HIL_STATE_QUATERNION: the true attitude, body rates, virtual position, velocity and
    acceleration (ground truth for the flight stack's log; the acceleration NED in milli-g
    as common.xml gives the unit); ``geo``: :func:`geodetic` of the readout if already
    computed. Sent at most every step: positional fields, the units from their one place."""
    lat, lon, alt = geo or geodetic(readout, plane)
    vn, ve, vd = enu_to_ned_xyz(*readout.velocity)
    an, ae, ad = enu_to_ned_xyz(*readout.acceleration)
    w, x, y, z = mavlink_quaternion_from_quat_wb(readout.quaternion)
    p, q, r = readout.body_rates
    speed_cm_s = U.cm_s_u16(math.sqrt(vn * vn + ve * ve + vd * vd))
    cm_s, milli_g = U.cm_s_i16, U.milli_g
    return mavlink.MAVLink_hil_state_quaternion_message(
        H.step_usec(readout.time_s), [w, x, y, z],  # time_usec, attitude_quaternion
        float(p), float(q), float(r),  # rollspeed, pitchspeed, yawspeed
        U.deg_e7(lat), U.deg_e7(lon), U.mm(alt),  # lat, lon, alt
        cm_s(vn), cm_s(ve), cm_s(vd),  # vx, vy, vz
        speed_cm_s, speed_cm_s,  # ind_airspeed, true_airspeed
        milli_g(an), milli_g(ae), milli_g(ad))  # xacc, yacc, zacc
