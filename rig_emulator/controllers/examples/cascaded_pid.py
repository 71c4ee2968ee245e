"""A cascaded PID in plain Python, as a user writes one: position PID -> tilt -> attitude PID.

Both loops, u1 and body torques out (the rig's allocation does the rest). It reads what the
onboard computer has (``obs``) and its gains (``self.params``); no numba. It takes the numbers
it works with as Python floats (``.tolist()`` of the read-only numpy views, once a call):
arithmetic on floats is about three times cheaper than on the numpy scalars that indexing a
view gives (docs/explanation/controller-speed.md). The built-in ``pid`` strategy (and its
compiled twin, :mod:`.pid`) also shapes the attitude target with a reference filter; this one
does not. ``rig-emulator simulate --scenario helix --controller
rig_emulator.controllers.examples.cascaded_pid:CascadedPID``; its speed is the
``plugin-python-cascaded`` probe of ``python -m benchmarks --only plugins``.
"""

import math

from rig_emulator.controllers import Command, Controller


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
        pos, vel = obs.position.tolist(), obs.velocity.tolist()
        kp, ki, kd = p.pos_kp.tolist(), p.pos_ki.tolist(), p.pos_kd.tolist()
        acc = [0.0, 0.0, 0.0]
        for i in range(3):  # position PID: the acceleration asked of each world axis
            e = r[i] - pos[i]
            self.pos_int[i] = min(max(self.pos_int[i] + e * dt, -lim), lim)
            acc[i] = a[i] + kp[i] * e + ki[i] * self.pos_int[i] + kd[i] * (v[i] - vel[i])
        euler, rates, inertia = obs.euler.tolist(), obs.euler_rates.tolist(), obs.inertia.tolist()
        phi, theta, psi_d, s = euler[0], euler[1], ref.yaw, math.sin(obs.max_tilt)
        u1 = m * (obs.gravity + acc[2]) / max(math.cos(phi) * math.cos(theta), math.cos(obs.max_tilt))
        ux, uy = m * acc[0] / u1, m * acc[1] / u1  # Eq. 34-35: the tilt of the thrust
        phi_d = math.asin(min(max(ux * math.sin(psi_d) - uy * math.cos(psi_d), -s), s))
        theta_d = math.asin(min(max((ux * math.cos(psi_d) + uy * math.sin(psi_d)) / math.cos(phi_d), -s), s))
        target, tau = (phi_d, theta_d, psi_d), [0.0, 0.0, 0.0]
        kp, ki, kd = p.att_kp.tolist(), p.att_ki.tolist(), p.att_kd.tolist()
        for i in range(3):  # attitude PID: Euler-frame torques
            e = target[i] - euler[i]
            if i == 2:
                e = (e + math.pi) % (2.0 * math.pi) - math.pi  # yaw: the shorter way round
            self.att_int[i] = min(max(self.att_int[i] + e * dt, -lim), lim)
            tau[i] = inertia[i] * (kp[i] * e + ki[i] * self.att_int[i] - kd[i] * rates[i])
        return Command((u1, tau[0], -tau[1], -tau[2]), target)  # Euler frame -> body FRD
