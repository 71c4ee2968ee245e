"""ArduPilot's servo outputs -> the rig's four motor voltage commands: the one place this
link scales PWM.

Outputs ``SERVO1..SERVO4`` (``pwm[0..3]`` of the servo packet) drive the rig's motors 1..4,
as the PX4 link's ``controls[0..3]`` do: motor 1 front, 2 right, 3 back, 4 left (a plus
frame, body FRD), motors 1 and 3 counter-clockwise seen from above. ArduCopter's frame that
matches it is the quad ``PLUSREV`` (``FRAME_CLASS 1``, ``FRAME_TYPE 6``: its motor 1 right
CW, 2 left CW, 3 front CCW, 4 back CCW), with its motors routed to these outputs by
``SERVOn_FUNCTION`` (``hilms.parm`` beside this file):

==========  ==============  =========================  ================
output      rig motor       ArduCopter PLUSREV motor   SERVOn_FUNCTION
==========  ==============  =========================  ================
SERVO1      1 front, CCW    Motor3 (0 deg, CCW)        35
SERVO2      2 right, CW     Motor1 (90 deg, CW)        33
SERVO3      3 back, CCW     Motor4 (180 deg, CCW)      36
SERVO4      4 left, CW      Motor2 (-90 deg, CW)       34
==========  ==============  =========================  ================

A pulse of ``PWM_MIN_US`` (1000 us) or less is a stopped motor, ``PWM_MAX_US`` (2000 us) full
command: ``u = (pwm - 1000) / 1000`` clipped to 0..1, the motor driver's voltage command
``u x motors.voltage_max`` (15 V); the thrust is the plant's motor curve of it (convex on the
default plant, Eq. 40's straight line on the ideal one; ArduCopter's thrust model of it:
docs/how-to/flight-stacks.md). ArduCopter's ``MOT_PWM_MIN`` / ``MOT_PWM_MAX`` must be
1000 / 2000.
"""

from __future__ import annotations

PWM_MIN_US = 1000.0
PWM_MAX_US = 2000.0
MOTORS = 4  # outputs SERVO1..SERVO4 drive motors 1..4


def motor_voltages(pwm_us, voltage_max_v: float) -> list:
    """The voltage commands (V) of motors 1..4 from the servo outputs ``pwm_us`` (us)."""
    span = PWM_MAX_US - PWM_MIN_US
    out = []
    for pwm in pwm_us[0:MOTORS]:
        u = (pwm - PWM_MIN_US) / span
        u = 0.0 if 0.0 > u else (1.0 if u > 1.0 else u)
        out.append(u * voltage_max_v)
    return out
