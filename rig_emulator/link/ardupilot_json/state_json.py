"""The physics' answer to one ArduPilot frame: one line of JSON from a
:class:`~rig_emulator.simulation.hil_readout.HilReadout`.

What ArduPilot's JSON interface reads (``libraries/SITL/SIM_JSON.cpp``, ``keytable``), all
required but the attitude, of which one form is (the quaternion wins):

================  =============================================================  ============
key               what the rig sends                                             unit, frame
================  =============================================================  ============
``timestamp``     the end of the step, simulated time since the session started  s
``imu.gyro``      the IMU modules' calibrated ensemble                           rad/s, body FRD
``imu.accel_body`` the ensemble's specific force plus the virtual translation's  m/s^2, body FRD
                  acceleration in the body, ``R^T a_virtual`` (level at rest:
                  ``[0, 0, -9.81]``)
``position``      the virtual translation (Eq. 1) from home                      m, NED
``velocity``      its velocity                                                   m/s, NED
``quaternion``    the true attitude, body FRD to NED, ``[w, x, y, z]``           -
================  =============================================================  ============

ArduPilot makes its GPS, barometer and compass itself from position, velocity and attitude
(with its own ``SIM_*`` noise and World Magnetic Model): the rig's magnetometers and load cells
stay on the ground link. The accelerometer is a flying vehicle's (as on the PX4 link): a tilted
rig accelerates sideways and its accelerometer keeps showing the thrust direction, so that it
agrees with the GPS velocity ArduPilot's EKF fuses.

The parser on the other side is ``strstr`` and ``sscanf("[%f, %f, %f]")`` after skipping
``"key":``, not a JSON parser: the line must be compact (no space after a colon), each key
must appear once and no key may hold another's name. The line is framed by newlines
(``"\\n{...}\\n"``; ArduPilot takes the last whole line it has). ``timestamp`` and ``position``,
which ArduPilot reads as doubles, are written in Python's shortest round-trip form (``repr``),
the rest (read as floats) with 9 significant digits, which ``%f`` reads back within one unit
in the last place of a float of the double itself (and three times cheaper to write); a value
that is not finite (a diverged plant) is written as JSON's ``NaN`` / ``Infinity``, which they
read as well.
"""

from __future__ import annotations

from protocol.frames import enu_to_ned_xyz, mavlink_quaternion_from_quat_wb

#: ``timestamp`` and ``position`` are doubles in ArduPilot (``%r``), the others floats (``%.9g``)
_LINE = ('\n{"timestamp":%r,"imu":{"gyro":[%.9g,%.9g,%.9g],"accel_body":[%.9g,%.9g,%.9g]},'
         '"position":[%r,%r,%r],"velocity":[%.9g,%.9g,%.9g],"quaternion":[%.9g,%.9g,%.9g,%.9g]}\n')


def state_line(readout) -> bytes:
    """The JSON line (ASCII bytes, framed by newlines) answering the frame that ended in ``readout``."""
    g, a = readout.gyro, readout.accel
    pn, pe, pd = enu_to_ned_xyz(*readout.position)
    vn, ve, vd = enu_to_ned_xyz(*readout.velocity)
    w, x, y, z = mavlink_quaternion_from_quat_wb(readout.quaternion)
    line = (_LINE % (
        float(readout.time_s),
        float(g[0]), float(g[1]), float(g[2]),
        float(a[0]), float(a[1]), float(a[2]),
        float(pn), float(pe), float(pd),
        float(vn), float(ve), float(vd),
        w, x, y, z,
    )).encode("ascii")
    if b"nan" in line or b"inf" in line:  # no key holds either
        line = line.replace(b"nan", b"NaN").replace(b"inf", b"Infinity")
    return line
