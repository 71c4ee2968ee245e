"""Studies behind the explanation pages: each measures one question the paper leaves open.

Run one with ``python -m gcs_tools.studies NAME [ARGS]`` (``--help`` after NAME for its
options; ``python -m gcs_tools.studies`` lists them). They are long headless sweeps, not part
of the test suite; the documentation includes their output with the command beside it.
"""

#: study name -> (module, one line on what it measures)
STUDIES = {
    "readings": ("readings", "every reading of Eq. 41 and of the motor ceiling against every claim of the paper"),
    "chattering": ("chattering", "where the FLC's chattering on the hardware rig comes from (Fig. 12)"),
    "table6": ("table6", "Table 6's altitude errors: Eq. 46's jump at t = 12 s through the mixer"),
    "thrust-loop": ("thrust_loop", "the load-cell thrust loop's time constant against Fig. 17, and faulted cells"),
    "paper-numbers": ("paper_numbers",
                      "the paper's 18 numbers at one setting (point) or over a scan of one (rate share, delay, yaw)"),
    "faults": ("faults", "how the rig degrades under each fault: estimation error, tracking error, failsafe"),
    "px4-reposition": ("px4_reposition", "PX4 SITL flying the rig: hover and 5 m repositions per airframe "
                                         "(needs a PX4 build)"),
    "ardupilot-move": ("ardupilot_move", "ArduCopter SITL flying the rig: hover and a 5 m move per parameter "
                                         "variant (needs an ArduPilot build)"),
    "served-takeoff": ("served_takeoff", "the served rig armed from its hang into a mission take-off: where the "
                                         "onboard and the physics vehicle go"),
    "served-sysid": ("served_sysid", "the identification flight served and logged by a ground station, read by "
                                     "rig-gcs identify --tlog at each telemetry rate"),
    "px4-semantics": ("px4_semantics", "PX4's mode, offboard, fence and mission semantics on a served rig: the "
                                       "figures of the offboard-and-fences guide"),
}
