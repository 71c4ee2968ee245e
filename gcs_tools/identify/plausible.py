"""Where a rig of this build plausibly has each identifiable effect, and the check that an estimate is there.

The schema's ranges (``rig-emulator params``) are what the emulator accepts; these are what a HILMS rig
built as the paper's is likely to have: motors and propellers within 10 % of each other, a thrust bias
of a running motor up to 100 gr.F low, a curve between Eq. 40's straight line and a propeller's square law,
a 5-25 ms sensing-to-actuation delay, a lubricated spherical joint, a centre of gravity within 15 mm of
the joint laterally and 10-50 mm below it, a random torque of a few per cent of the hover authority.
The calibration study draws its hidden values here (gcs_tools/identify/study.py). An estimate whose whole
95 % interval lies outside, by more than :data:`MARGIN` of the range, is reported by the model check: the model explains the log only with a value
no such rig has, as when a mass hangs on an arm (its moment reads as a centre of gravity 15 mm off for
100 g at 0.33 m).
"""

from __future__ import annotations

from dataclasses import dataclass

#: key -> (low, high), SI (the thrust bias in gr.F, as its key says)
PLAUSIBLE_RANGES = {
    "motors.thrust_gain[0]": (0.9, 1.1), "motors.thrust_gain[1]": (0.9, 1.1),
    "motors.thrust_gain[2]": (0.9, 1.1), "motors.thrust_gain[3]": (0.9, 1.1),
    "motors.thrust_bias_grf": (-100.0, 0.0),
    "motors.curve_exponent": (1.3, 2.1),
    "control.actuation_delay": (0.005, 0.025),
    "joint.viscous[0]": (0.0, 0.06), "joint.viscous[1]": (0.0, 0.06), "joint.viscous[2]": (0.0, 0.06),
    "joint.coulomb[0]": (0.0, 0.1), "joint.coulomb[1]": (0.0, 0.1), "joint.coulomb[2]": (0.0, 0.05),
    "joint.cog_offset[0]": (-0.015, 0.015), "joint.cog_offset[1]": (-0.015, 0.015),
    "joint.cog_offset[2]": (0.01, 0.05),
    "disturbance.torque_noise[0]": (0.005, 0.04), "disturbance.torque_noise[1]": (0.005, 0.04),
    "disturbance.torque_noise[2]": (0.005, 0.04),
}


#: how far beyond its range (a share of the range) an interval must lie: a value drawn near the edge of its
#: range is estimated with an error of a few per cent of it (the viscous friction: docs/how-to/identify.md)
MARGIN = 0.1


@dataclass
class OutOfRange:
    """An estimate whose 95 % interval lies outside its plausible range (and the margin)."""

    key: str
    value: float
    lo: float
    hi: float

    def text(self) -> str:
        a, b = PLAUSIBLE_RANGES[self.key]
        return (f"{self.key} = {self.value:.4g} [{self.lo:.4g}, {self.hi:.4g}] lies outside what a rig of this build "
                f"plausibly has ({a:g}..{b:g}): an effect the model lacks reads as this one (a mass on an arm "
                f"as the centre of gravity, a thrust loss as a gain)")


def range_findings(estimates) -> list:
    """:class:`OutOfRange` for each estimate (``.key``, ``.value``, ``.lo``, ``.hi``, ``.held``) with a range
    here whose interval misses it by more than the margin."""
    out = []
    for e in estimates:
        r = PLAUSIBLE_RANGES.get(e.key)
        if r is None or getattr(e, "held", False):
            continue
        margin = MARGIN * (r[1] - r[0])
        if e.hi < r[0] - margin or e.lo > r[1] + margin:
            out.append(OutOfRange(e.key, e.value, e.lo, e.hi))
    return out
