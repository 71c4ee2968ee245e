"""ArduPilot SITL in the loop: the rig as the physics of its JSON simulator interface (``serve --ardupilot-json``)."""
