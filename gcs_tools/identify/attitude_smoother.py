"""The attitude of an identification log, smoothed after the flight: the gyros' detail on the attitude
estimate's long-term level (a zero-phase complementary smoother).

The rig's complementary filter (rig_emulator/estimation/complementary.py) runs forward in time and
leans on its accelerometers, which on a swinging rig also feel the modules' own tangential and
centripetal accelerations: in the identification flight's disarmed swings its roll or pitch is
0.3 deg off, in step with the swing. In the torque balance that error turns the pendulum's torque
(``m g r_z`` about 0.5-1 N m per rad) into a torque in phase with the rate, which the regression takes
for viscous friction (measured: the viscous estimates 0.005-0.02 N m s/rad high, far outside their
intervals; with the true attitude they are not).

After the flight both directions of time are available, so the attitude is rebuilt as engineers
post-process flight logs: the Euler rates from the logged body rates (the rig's kinematics,
rig_emulator/physics/rotation.py ``euler_rates_from_body_rates``), integrated, carry everything above
:data:`CROSSOVER_HZ`; the estimate carries what is below, both through the same zero-phase Butterworth
filter (``scipy.signal.sosfiltfilt``: no lag either side). Measured on the identification flight
(`hilms`, seeds 1-2): roll and pitch errors in the swings 0.30 deg -> 0.025-0.05 deg rms, in the
chirps 0.06 -> 0.01-0.02 deg. Yaw is left as logged (gravity does not depend on it).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.signal import butter, sosfiltfilt

CROSSOVER_HZ = 0.05


def smoothed_attitude(t: np.ndarray, euler: np.ndarray, omega: np.ndarray, crossover_hz: float = CROSSOVER_HZ):
    """(n, 3) paper phi, theta, psi (rad) from the logged estimate ``euler`` and body rates ``omega``
    (B = FRD, rad/s) at times ``t`` (s)."""
    phi, theta = euler[:, 0], euler[:, 1]
    p, q, r = omega[:, 0], -omega[:, 1], -omega[:, 2]  # the paper's angles' own body rates (rotation.py)
    dphi = p + (q * np.sin(phi) + r * np.cos(phi)) * np.tan(theta)
    dtheta = q * np.cos(phi) - r * np.sin(phi)
    fs = 1.0 / float(np.median(np.diff(t)))
    if t.size < 64 or crossover_hz >= 0.5 * fs:
        return euler.copy()
    sos = butter(2, crossover_hz, fs=fs, output="sos")
    out = euler.copy()
    for j, rate in ((0, dphi), (1, dtheta)):
        integral = cumulative_trapezoid(rate, t, initial=0.0)
        out[:, j] = sosfiltfilt(sos, euler[:, j] - integral) + integral
    return out
