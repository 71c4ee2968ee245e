"""Pre-arm checks, as a flight controller runs them before it lets the motors spin.

:func:`prearm_failure` reads a :class:`~rig_emulator.simulation.live.RigSnapshot` (the
attitude the firmware estimates, its supervisor's findings and the injected faults) and
returns the first reason not to arm, or ``None``. Checks, in order:

* an injected fault on any IMU module, load cell or motor (a sensor or motor fault);
* body rate beyond ``prearm.max_rate_deg_s`` (the rig still turns, e.g. after a failsafe trip);
* roll or pitch beyond ``prearm.max_tilt_deg`` (the rig is not level);
* the fused attitude estimate invalid, or IMU modules / load cells flagged by the estimators
  (estimator unhealthy).

Reading: this is how the rig recovers from a loss-of-control failsafe: the latch clears on
arming, which these checks allow only once the rig is level, still and its estimator healthy.
"""

from __future__ import annotations

import math

from rig_emulator.simulation.faults import FaultStatus


def prearm_failure(snap, cfg) -> str | None:
    """The reason arming is refused now, or None when every check passes."""
    f: FaultStatus | None = snap.faults
    if f is not None:
        for name, codes in (("IMU module", f.imu_faults), ("load cell", f.cell_faults), ("motor", f.motor_faults)):
            for i, code in enumerate(codes):
                if code:
                    index = i if name == "IMU module" else i + 1
                    return f"{name} {index} has an injected fault (clear it first)"
    rate = math.degrees(math.sqrt(sum(w * w for w in snap.body_rates)))
    limit = cfg["prearm.max_rate_deg_s"]
    if not rate <= limit:
        return f"still rotating: {rate:.0f} deg/s > {limit:g} deg/s"
    tilt = math.degrees(max(abs(snap.euler[0]), abs(snap.euler[1])))
    limit = cfg["prearm.max_tilt_deg"]
    if not tilt <= limit:
        return f"not level: tilt {tilt:.0f} deg > {limit:g} deg"
    if f is not None:
        if f.estimate_invalid:
            return "attitude estimate invalid (estimator unhealthy)"
        if f.imu_flagged_any:
            return "IMU modules rejected by the estimator (estimator unhealthy)"
        if f.cells_flagged:
            return "load cells rejected by the estimator"
    return None
