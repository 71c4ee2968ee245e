"""An LQR attitude controller behind the rig's own position loop: a plug-in in well under 100 lines.

Per Euler axis the attitude error obeys a double integrator: with ``e = r - angle`` and the
commanded angular acceleration ``u = r'' + v``, ``e'' = -v``. Adding the error integral gives
the state ``z = (int e, e, e')`` with ``z' = A z + B v`` (``A`` the 3x3 shift, ``B = (0, 0, 1)``
after the sign flip); the gain ``K = R^-1 B^T P`` of the continuous-time algebraic Riccati
equation ``A^T P + P A - P B R^-1 B^T P + Q = 0`` (``scipy.linalg.solve_continuous_are``)
minimises ``int z^T Q z + R v^2``. The torque about each Euler axis is
``tau = I (r'' + K z)``, turned to body axes like the rig's own laws (docs/explanation/conventions.md).

It replaces the attitude loop only: the configured strategy's position loop (the paper's
fuzzy one with ``smc-flc``) hands it the shaped attitude reference and u1
(``obs.attitude_target``, ``obs.thrust_target``); it commands u1 and body torques.
``rig-gcs reproduce --only helix --controller rig_emulator.controllers.examples.lqr:LQRAttitude``
puts its Table 6 row next to the paper's (docs/how-to/your-controller.md).
"""

import math

import numba
import numpy as np
import scipy.linalg

from rig_emulator.control import plugin_layout as L
from rig_emulator.controllers import CompiledController


def lqr_gains(q_int: float, q_angle: float, q_rate: float, r: float) -> np.ndarray:
    """(k_int, k_angle, k_rate) of the integral-augmented double integrator."""
    a = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    b = np.array([[0.0], [0.0], [1.0]])
    p = scipy.linalg.solve_continuous_are(a, b, np.diag([q_int, q_angle, q_rate]), np.array([[r]]))
    return (b.T @ p / r).ravel()


@numba.njit(cache=True)
def lqr_kernel(t, obs, p, s, out):
    # params: k (3 axes x (int, angle, rate)), integral limit; state: the error integrals
    dt = obs[L.O_DT]
    out[L.C_CMD] = obs[L.O_THRUST_TARGET]
    for i in range(3):
        e = obs[L.O_ATT_TARGET + i] - obs[L.O_EULER + i]
        if i == 2:  # yaw: the shorter way round
            e = e - 2.0 * math.pi * math.floor((e + math.pi) / (2.0 * math.pi))
        de = obs[L.O_ATT_RATE_TARGET + i] - obs[L.O_EULER_RATE + i]
        s[i] = min(max(s[i] + e * dt, -p[9]), p[9])
        acc = obs[L.O_ATT_ACC_TARGET + i] + p[3 * i] * s[i] + p[3 * i + 1] * e + p[3 * i + 2] * de
        tau = obs[L.O_IXX + i] * acc
        out[L.C_CMD + 1 + i] = tau if i == 0 else -tau  # Euler frame -> body FRD
        out[L.C_ATT_DES + i] = obs[L.O_ATT_TARGET + i]
        out[L.C_ATT_RATE_DES + i] = obs[L.O_ATT_RATE_TARGET + i]
    return 0


class LQRAttitude(CompiledController):
    """LQR on each Euler axis; weights Q = diag(q_int, q_angle, q_rate), R = r (per axis: roll,
    pitch, yaw). The gains are parameters (``LQR_K1..K9``) a ground station can retune."""

    replaces = "attitude"
    commands = "torques"
    kernel = lqr_kernel
    state_size = 3
    param_prefix = "LQR_"
    weights = {"roll": (400.0, 1e4, 100.0, 1.0), "pitch": (400.0, 1e4, 100.0, 1.0), "yaw": (100.0, 1e3, 30.0, 1.0)}
    params = {"k": [0.0] * 9, "i_limit": 0.5}  # LQR_K1..LQR_K9, LQR_I_LIMIT

    def __init__(self, **params):
        super().__init__(**params)
        if "k" not in params:
            self.params.set("k", np.concatenate([lqr_gains(*self.weights[a]) for a in ("roll", "pitch", "yaw")]))
