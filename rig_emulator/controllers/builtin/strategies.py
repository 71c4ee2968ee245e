"""Controller strategies by name: which law runs the position loop and which the attitude loop.

* ``smc-flc`` (default, the paper's proposal, Sec. 3-3): FLC position, SMC attitude.
* ``flc``: FLC for all six DOF (Sec. 4-3).
* ``smc``: SMC attitude (Sec. 3-1) with a sliding-mode position loop (Eq. 5-9 applied to
  the double integrator of Eq. 33; boundary-layer switching).
* ``pid``: a cascaded PID baseline.
"""

FLC = 0
SMC = 1
PID = 2

STRATEGY_LAWS = {
    "smc-flc": (FLC, SMC),
    "flc": (FLC, FLC),
    "smc": (SMC, SMC),
    "pid": (PID, PID),
}


def laws(name: str) -> tuple[int, int]:
    """(position law, attitude law) of a strategy name."""
    try:
        return STRATEGY_LAWS[name]
    except KeyError:
        raise ValueError(f"control.strategy = {name!r}: must be one of {', '.join(STRATEGY_LAWS)}") from None
