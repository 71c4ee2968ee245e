"""The rig's own virtual translation: Eq. 1 integrated from what its sensors say.

On the HILMS the translation is never measured: the onboard computer integrates Eq. 1
from the filtered load-cell thrusts and the estimated attitude (Sec. 4-1). The
disturbance forces of Eq. 1 are software inputs of the rig, so they enter here as they
do in the physics. Semi-implicit Euler at the control period; the virtual ground (if on)
applies as in the physics (:func:`rig_emulator.physics.integrator.apply_ground`): with
``sim.ground_contact = "hold"`` a vehicle standing on it keeps its place
(:func:`rig_emulator.physics.ground.hold_on_ground`), else it slides on a frictionless ground
and rests only with a measured thrust below 5 % of the weight.
"""

from rig_emulator._jit import jit
from rig_emulator.control.thrust_direction import thrust_direction
from rig_emulator.physics.ground import hold_on_ground


@jit(nrt=False)  # a call, not inline="always": inlining it cost most of the cold compile
def onboard_translation_step(dt, phi, theta, psi, u1, mass, g, fwx, fwy, fwz, ground, ground_hold, state):
    """Advance ``state`` = (position 0:3, velocity 3:6) by ``dt`` (world ENU); ``ground``:
    ``sim.ground``, ``ground_hold``: ``sim.ground_contact == "hold"``."""
    x_before = state[0]
    y_before = state[1]
    ux, uy, uz = thrust_direction(phi, theta, psi)
    inv_m = 1.0 / mass
    state[3] += (ux * u1 + fwx) * inv_m * dt
    state[4] += (uy * u1 + fwy) * inv_m * dt
    state[5] += ((uz * u1 + fwz) * inv_m - g) * dt
    state[0] += state[3] * dt
    state[1] += state[4] * dt
    state[2] += state[5] * dt
    if ground and state[2] <= 0.0:
        state[2] = 0.0
        if state[5] < 0.0:
            state[5] = 0.0
        if ground_hold:
            hold_on_ground(state, x_before, y_before)
        elif u1 < 0.05 * mass * g:  # motors stopped on the ground: resting, as in the physics
            state[3] = 0.0
            state[4] = 0.0
