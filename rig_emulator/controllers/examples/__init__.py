"""Example controller plug-ins (docs/how-to/your-controller.md).

* :mod:`.pid` - the rig's built-in cascaded PID strategy re-written as a plug-in (both loops,
  torques out); flies bit-for-bit like ``control.strategy = "pid"`` (tested to 1e-9).
* :mod:`.cascaded_pid` - a cascaded PID in plain Python, as a user writes one (both loops).
* :mod:`.lqr` - an LQR attitude controller behind the rig's fuzzy position loop.
* :mod:`.hover` - the smallest possible plug-in (plain Python, motor thrusts out).

The built-in strategies' own laws are :mod:`rig_emulator.controllers.builtin`.
"""
