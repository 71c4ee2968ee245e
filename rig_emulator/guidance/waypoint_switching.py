"""The Sec. 4-4 waypoint logic of :mod:`protocol.waypoint_switching`, compiled.

``protocol`` holds the shared logic as plain Python (it imports nothing from the rig); here
the rig compiles those very functions with :func:`rig_emulator._jit.jit` (cached, keyed on
the source of ``protocol/waypoint_switching.py`` too, see ``COMPILED_ROOTS``). The step loop
(:mod:`rig_emulator.guidance.runner`) and the ground tools (:mod:`gcs_tools.fly`) call these,
so the rig and ``rig-gcs fly`` switch on the same compiled arithmetic.
"""

from protocol import waypoint_switching as _shared
from rig_emulator._jit import jit

leg_duration = jit(_shared.leg_duration)
line_setpoint = jit(nrt=False)(_shared.line_setpoint)  # takes arrays, called in the step loop
waypoint_reached = jit(_shared.waypoint_reached)
