"""The virtual ground's resting contact: a vehicle standing on it stays where it stands.

The HILMS cannot translate; its onboard computer integrates a *virtual* vehicle (Eq. 1) and the
emulator integrates a true one beside it (the physics state), both over a virtual ground at
Z = 0 (``sim.ground``). What the ground does to a vehicle standing on it is a reading, set by
``sim.ground_contact``:

* ``"frictionless"`` (the ideal plant): the ground only stops the vehicle sinking; a tilted
  thrust below the weight slides it across the ground at up to metres per second, and it
  rests only with the motors (nearly) stopped.
* ``"hold"`` (the hardware rig, ``hilms``): :func:`hold_on_ground`.

Why the hold is the right reading for this rig: the attitude the virtual vehicle is integrated
with is the rig's, and a disarmed rig hangs tilted on its joint (``joint.cog_offset``: about
13 deg on ``hilms``). A real vehicle standing on flat ground is levelled by its landing gear,
whose contact forces (normal force and static friction at several feet) cancel whatever
horizontal thrust it has until it lifts off; the hanging tilt is the joint's, not a vehicle's
on the ground. Flight simulators model the contact so: ArduPilot's SITL
(``libraries/SITL/SIM_Aircraft.cpp``, ``GROUND_BEHAVIOR_NO_MOVEMENT``, the multicopters' ground
behaviour) sets the horizontal velocity on the ground to the ground's own (zero here) and
stops any sinking, and the vehicle leaves the ground only when its vertical acceleration lifts
it. Coulomb friction on the rig's tilt would not do: with the hanging tilt the horizontal
thrust grows while the normal force vanishes as the thrust nears the weight, so the vehicle
would still be thrown at every take-off, which no vehicle standing on its gear does.
"""

from rig_emulator._jit import jit


@jit(nrt=False)
def hold_on_ground(s, x_before, y_before):
    """Resting contact on the virtual ground: hold the horizontal position, stop the motion.

    Where it acts: on a translational state ``s`` (position 0:3, velocity 3:6, world ENU; the
    physics state :data:`rig_emulator.physics.state` and the onboard virtual position of
    :func:`rig_emulator.estimation.onboard_position.onboard_translation_step` share that layout)
    after a step that ended with the vehicle on the ground (Z <= 0, already put back to Z = 0 with
    no downward velocity). ``x_before``, ``y_before``: the horizontal position at the start of the
    step, which the vehicle keeps. The vehicle lifts off on the first step whose vertical thrust
    exceeds its weight (Z > 0 at the end of the step), so a climbing take-off is not held.

    Source: ArduPilot SITL's ``GROUND_BEHAVIOR_NO_MOVEMENT`` (``SIM_Aircraft.cpp``: on the ground
    the horizontal velocity follows the ground's, no sinking); the argument for this rig is in the
    module docstring.
    """
    s[0] = x_before
    s[1] = y_before
    s[3] = 0.0
    s[4] = 0.0
