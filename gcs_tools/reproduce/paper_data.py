"""The paper's published numbers and claims, each with where it is printed.

Only what the paper states is here (tables, numbers in the text, the set-ups of the
experiments); the hardware figures (Figs. 12-19) carry no numbers beyond these. Section
numbers refer to ``hilms-paper.md``.
"""

from __future__ import annotations

from protocol.mean_error import PAPER_TABLE_6

#: Eq. 44 / Fig. 13: phi_des = theta_des = 10 sin(omega t) deg at omega = 0.4 rad/s.
HARMONIC_OMEGA = 0.4
HARMONIC_AMPLITUDE_DEG = 10.0

#: Fig. 14: the harmonic frequency runs from 0.1 to 2 rad/s (the paper does not list its grid).
SWEEP_OMEGA_RANGE = (0.1, 2.0)

#: Table 4: average over the frequencies of Fig. 14 of the mean error (Eq. 45), degrees.
TABLE_4 = {
    "smc": {"phi_deg": 1.1483, "theta_deg": 1.1025},
    "flc": {"phi_deg": 0.9854, "theta_deg": 0.8231},
}
#: Sec. 4-2 text after Table 4: FLC improves on SMC by 14 % (roll) and 25.3 % (pitch).
TABLE_4_FLC_IMPROVEMENT_PCT = {"phi_deg": 14.0, "theta_deg": 25.3}

#: Sec. 4-2, Fig. 15: extra masses of 40 to 100 g at 0.33 m from the centre on two arms.
EXTRA_MASSES_KG = (0.04, 0.06, 0.08, 0.10)
EXTRA_MASS_DISTANCE_M = 0.33

#: Table 6: mean errors of the line-then-helix of Eq. 46 (deg, m).
TABLE_6 = PAPER_TABLE_6
#: Sec. 4-3 and Sec. 5: SMC-FLC improves position tracking (X and Y) by about 9 % over FLC.
HELIX_XY_IMPROVEMENT_PCT = 9.0

#: Fig. 17: the altitude run lasts 250 s.
ALTITUDE_RUN_S = 250.0

#: Sec. 4-4, Fig. 19: a 5 m x 3 m rectangle at one altitude, 8 cm switching radius; mean errors in X and Y (m).
RECTANGLE_SIZE_M = (5.0, 3.0)
RECTANGLE_SWITCHING_RADIUS_M = 0.08
RECTANGLE_ME = {"x_m": 0.0923, "y_m": 0.08562}

#: The paper's claims the report gives a verdict on: id -> (claim, where the paper makes it).
CLAIMS = {
    "flc_tracks_better": (
        "Without disturbances FLC tracks roll and pitch better than SMC (14 % and 25.3 % lower mean error)",
        "Sec. 4-2, Fig. 14, Table 4"),
    "smc_settles_faster": ("SMC settles faster than FLC after a shock on an arm", "Sec. 4-2, Fig. 12"),
    "flc_no_chattering": ("FLC eliminates the chattering SMC shows in hover with shocks", "Sec. 4-2, Fig. 12"),
    "flc_less_overshoot": ("FLC overshoots less than SMC after a shock", "Sec. 4-2, Fig. 12"),
    "both_track_harmonic": ("Both controllers track the 10 deg harmonic roll and pitch at 0.4 rad/s",
                            "Sec. 4-2, Eq. 44, Fig. 13"),
    "flc_flat_over_frequency": ("FLC's mean error is almost unchanged over 0.1-2 rad/s", "Sec. 4-2, Fig. 14"),
    "smc_best_at_moderate": ("SMC does best at a moderate frequency, not the slowest or fastest",
                             "Sec. 4-2, Fig. 14"),
    "flc_smoother_extra_mass": ("With 40-100 g extra masses FLC responds more smoothly than SMC",
                                "Sec. 4-2, Fig. 15"),
    "smc_holds_extra_mass": ("SMC still restores the attitude with extra masses (with decreased performance)",
                             "Sec. 4-2, Fig. 15"),
    "smcflc_beats_flc_9pct": ("SMC-FLC tracks X and Y about 9 % better than FLC", "Sec. 4-3, Table 6, Sec. 5"),
    "smcflc_better_attitude": ("SMC-FLC has lower attitude mean errors than FLC on the helix", "Sec. 4-3, Table 6"),
    "smcflc_smoother_thrust": ("SMC-FLC's motor thrusts fluctuate less at high frequency than FLC's",
                               "Sec. 4-3, Fig. 18"),
    "iir_causes_altitude_lag": ("The load cells' IIR filter delay causes the altitude lag", "Sec. 4-3, Figs. 16-17"),
    "altitude_error_shrinks": ("Over a 250 s run the altitude error decreases with time", "Sec. 4-3, Fig. 17"),
    "rectangle_all_waypoints": ("The rig passes through every waypoint of the 5 m x 3 m rectangle with 8 cm switching",
                                "Sec. 4-4, Fig. 19"),
    "rectangle_mean_errors": ("Mean errors in X and Y of the rectangle are 0.0923 m and 0.08562 m",
                              "Sec. 4-4, Fig. 19"),
}
