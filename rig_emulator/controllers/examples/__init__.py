"""Example controller plug-ins (docs/YOUR_CONTROLLER.md).

* :mod:`.pid` - the rig's built-in cascaded PID strategy re-written as a plug-in (both loops,
  torques out); flies bit-for-bit like ``control.strategy = "pid"`` (tested to 1e-9).
* :mod:`.lqr` - an LQR attitude controller behind the rig's fuzzy position loop.
* :mod:`.hover` - the smallest possible plug-in (plain Python, motor thrusts out).
"""
