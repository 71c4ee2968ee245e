"""A cascaded PID in plain Python, as a user writes one: position PID -> tilt -> attitude PID.

Both loops, u1 and body torques out (the rig's allocation does the rest). It reads what the
onboard computer has (``obs``) and its gains (``self.params``); no numba. It is written as fast
Python is written (docs/explanation/controller-speed.md): the numbers it works with are taken
as Python floats once a call (``.tolist()`` of the read-only numpy views; arithmetic on floats
is about three times cheaper than on the numpy scalars that indexing a view gives), the
integrators are clamped with comparisons rather than ``min(max(...))`` calls, and ``math``'s
functions are module names. The built-in ``pid`` strategy (and its
compiled twin, :mod:`.pid`) also shapes the attitude target with a reference filter; this one
does not. ``rig-emulator simulate --scenario helix --controller
rig_emulator.controllers.examples.cascaded_pid:CascadedPID``; its speed is the
``plugin-python-cascaded`` probe of ``python -m benchmarks --only plugins``.
"""

import math

from rig_emulator.controllers import Command, Controller

sin, cos, asin, pi = math.sin, math.cos, math.asin, math.pi


class CascadedPID(Controller):
    replaces, commands = "both", "torques"
    param_prefix = "CPID_"
    params = {"pos_kp": [2.0, 2.0, 4.0], "pos_ki": [0.2, 0.2, 0.8], "pos_kd": [2.5, 2.5, 4.0],
              "att_kp": [100.0, 100.0, 16.0], "att_ki": [20.0, 20.0, 2.0], "att_kd": [20.0, 20.0, 8.0],
              "i_limit": 2.0}

    def reset(self):
        self.pos_int = [0.0, 0.0, 0.0]
        self.att_int = [0.0, 0.0, 0.0]

    def update(self, t, obs):
        p, dt, ref, lim, m = self.params, obs.dt, obs.reference, self.params.i_limit, obs.mass
        r, v, a = ref.position.tolist(), ref.velocity.tolist(), ref.acceleration.tolist()
        pos, vel, integral = obs.position.tolist(), obs.velocity.tolist(), self.pos_int
        kp, ki, kd, acc = p.pos_kp.tolist(), p.pos_ki.tolist(), p.pos_kd.tolist(), [0.0, 0.0, 0.0]
        for i in (0, 1, 2):  # position PID: the acceleration asked of each world axis
            e = r[i] - pos[i]
            s = integral[i] + e * dt
            integral[i] = s if -lim < s < lim else (lim if s > 0.0 else -lim)
            acc[i] = a[i] + kp[i] * e + ki[i] * integral[i] + kd[i] * (v[i] - vel[i])
        phi, theta, psi = obs.euler.tolist()
        psi_d, s = ref.yaw, sin(obs.max_tilt)
        u1 = m * (obs.gravity + acc[2]) / max(cos(phi) * cos(theta), cos(obs.max_tilt))
        ux, uy = m * acc[0] / u1, m * acc[1] / u1  # Eq. 34-35: the tilt of the thrust
        phi_d = asin(min(max(ux * sin(psi_d) - uy * cos(psi_d), -s), s))
        theta_d = asin(min(max((ux * cos(psi_d) + uy * sin(psi_d)) / cos(phi_d), -s), s))
        err = (phi_d - phi, theta_d - theta, (psi_d - psi + pi) % (2.0 * pi) - pi)  # yaw: the shorter way
        kp, ki, kd, integral = p.att_kp.tolist(), p.att_ki.tolist(), p.att_kd.tolist(), self.att_int
        rates, inertia, tau = obs.euler_rates.tolist(), obs.inertia.tolist(), [0.0, 0.0, 0.0]
        for i in (0, 1, 2):  # attitude PID: Euler-frame torques
            e = err[i]
            s = integral[i] + e * dt
            integral[i] = s if -lim < s < lim else (lim if s > 0.0 else -lim)
            tau[i] = inertia[i] * (kp[i] * e + ki[i] * integral[i] - kd[i] * rates[i])
        return Command((u1, tau[0], -tau[1], -tau[2]), (phi_d, theta_d, psi_d))  # Euler frame -> body FRD
