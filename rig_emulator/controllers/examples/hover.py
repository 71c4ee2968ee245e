"""The smallest controller plug-in: plain Python, motor thrusts out, attitude held level.

A PD on roll and pitch, the altitude held by a PD on the onboard virtual height (Eq. 1),
mixed onto the four motors by hand (A6: motor 1 front, 2 right, 3 back, 4 left). It shows
the Python call path; ``rig-emulator simulate --scenario hover --controller
rig_emulator.controllers.examples.hover:LevelHover``.
"""

from rig_emulator.controllers import Controller


class LevelHover(Controller):
    replaces = "both"
    commands = "motor_thrusts"
    param_prefix = "HOV_"
    params = {"kp_att": 8.0, "kd_att": 2.0, "kp_z": 4.0, "kd_z": 3.0}
    param_info = {  # the ranges every change is checked against (config, --set, PARAM_SET)
        "kp_att": {"min": 0.0, "max": 100.0, "unit": "N/rad", "doc": "roll and pitch stiffness (per motor pair)"},
        "kd_att": {"min": 0.0, "max": 20.0, "unit": "N s/rad", "doc": "roll and pitch damping (per motor pair)"},
        "kp_z": {"min": 0.0, "max": 50.0, "unit": "1/s^2", "doc": "altitude stiffness"},
        "kd_z": {"min": 0.0, "max": 20.0, "unit": "1/s", "doc": "altitude damping"},
    }

    def update(self, t, obs):
        p = self.params
        phi, theta, _ = obs.euler
        dphi, dtheta, _ = obs.euler_rates
        z_err = obs.reference.position[2] - obs.position[2]
        u1 = obs.mass * (obs.gravity + p.kp_z * z_err - p.kd_z * obs.velocity[2])
        roll = -(p.kp_att * phi + p.kd_att * dphi)  # N per motor pair, about the roll axis
        pitch = -(p.kp_att * theta + p.kd_att * dtheta)
        f = u1 / 4.0
        # A6: u2 = l (F4 - F2) about body x (FRD); u3 = l (F1 - F3) about body y (FRD) = -pitch (FLU)
        return (f - pitch, f - roll, f + pitch, f + roll)
