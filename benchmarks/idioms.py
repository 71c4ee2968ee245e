"""`examples.cascaded_pid:CascadedPID` written two slower ways, for ``python -m benchmarks.plugin_share``:
the same law and the same numbers bit for bit (tests/benchmarks/test_bench_idioms.py), so what the
share table shows between them is the cost of the Python idiom alone
(docs/explanation/controller-speed.md, "Going faster").

* :class:`CascadedPIDBuiltins` - floats taken once a call as the example does, but the integrators
  clamped with ``min(max(...))``, loops over ``range(3)`` and ``math.sin`` looked up at every call;
* :class:`CascadedPIDNumpy` - the same, and the numbers read as numpy scalars by indexing the
  observation's views instead of ``.tolist()``.

Each ``update`` is written out whole, as a user would write it: a helper shared between them would add a
call to every update and measure itself along with the idiom.
"""

import math

from rig_emulator.controllers import Command
from rig_emulator.controllers.examples.cascaded_pid import CascadedPID


class CascadedPIDBuiltins(CascadedPID):
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


class CascadedPIDNumpy(CascadedPID):
    def update(self, t, obs):
        p, dt, ref, lim, m = self.params, obs.dt, obs.reference, self.params.i_limit, obs.mass
        r, v, a = ref.position, ref.velocity, ref.acceleration
        pos, vel = obs.position, obs.velocity
        kp, ki, kd = p.pos_kp, p.pos_ki, p.pos_kd
        acc = [0.0, 0.0, 0.0]
        for i in range(3):  # position PID: the acceleration asked of each world axis
            e = r[i] - pos[i]
            self.pos_int[i] = min(max(self.pos_int[i] + e * dt, -lim), lim)
            acc[i] = a[i] + kp[i] * e + ki[i] * self.pos_int[i] + kd[i] * (v[i] - vel[i])
        euler, rates, inertia = obs.euler, obs.euler_rates, obs.inertia
        phi, theta, psi_d, s = euler[0], euler[1], ref.yaw, math.sin(obs.max_tilt)
        u1 = m * (obs.gravity + acc[2]) / max(math.cos(phi) * math.cos(theta), math.cos(obs.max_tilt))
        ux, uy = m * acc[0] / u1, m * acc[1] / u1  # Eq. 34-35: the tilt of the thrust
        phi_d = math.asin(min(max(ux * math.sin(psi_d) - uy * math.cos(psi_d), -s), s))
        theta_d = math.asin(min(max((ux * math.cos(psi_d) + uy * math.sin(psi_d)) / math.cos(phi_d), -s), s))
        target, tau = (phi_d, theta_d, psi_d), [0.0, 0.0, 0.0]
        kp, ki, kd = p.att_kp, p.att_ki, p.att_kd
        for i in range(3):  # attitude PID: Euler-frame torques
            e = target[i] - euler[i]
            if i == 2:
                e = (e + math.pi) % (2.0 * math.pi) - math.pi  # yaw: the shorter way round
            self.att_int[i] = min(max(self.att_int[i] + e * dt, -lim), lim)
            tau[i] = inertia[i] * (kp[i] * e + ki[i] * self.att_int[i] - kd[i] * rates[i])
        return Command((u1, tau[0], -tau[1], -tau[2]), target)  # Euler frame -> body FRD
