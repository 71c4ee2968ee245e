"""STATUSTEXT for faults: each injection, each detection, the failsafe - once per change.

The rig exposes plain data: the list of fault injections (:meth:`LiveRig.fault_events`,
from the config's timed events or a command) and a
:class:`~rig_emulator.simulation.faults.FaultStatus` with what its supervisor detects.
:class:`FaultReporter` turns them into ``(severity, text)`` pairs after every chunk:

* an injection: WARNING ``"motor 1: thrust_loss 50 % injected"``, INFO ``"... fault cleared"``;
* the ensemble starts / stops rejecting a module: WARNING ``"ensemble rejects IMU module 2
  (accel, mag)"`` / INFO ``"ensemble accepts IMU module 2 again"``; the load-cell guards
  likewise;
* the fused attitude estimate becomes invalid / valid: CRITICAL / INFO;
* the loss-of-control failsafe trips: CRITICAL ``"loss of control: attitude error 97 deg >
  45 deg for 0.5 s; motors stopped, disarmed"``; it clears when the rig is armed again.
* a controller plug-in fails while flying (:attr:`LiveRig.plugin_failure`):
  CRITICAL ``"controller my_pkg.mod:MyController at t = 3.000 s: RuntimeError: ... (mod.py:41
  in update); motors stopped, disarmed; arm again to retry"``, and INFO when arming
  clears it.

Detections are debounced by the supervisor (``health.reject_window``, with hysteresis), so a
module rejected now and then is not reported and a faulty one is reported once; a flagged
module whose set of rejected sensors changes is not reported again.
"""

from __future__ import annotations

import math

from protocol.dialect import mavlink as M
from rig_emulator.control.supervisor import ALERT_ATTITUDE, ALERT_ESTIMATE, ALERT_RATE, INVALID_ACCEL, INVALID_GYRO
from rig_emulator.simulation.faults import FaultEvent, FaultStatus

KINDS = ("gyro", "accel", "mag")


def injection_text(e: FaultEvent) -> tuple[int, str]:
    """The STATUSTEXT of one injection."""
    if e.mode == "none":
        return M.MAV_SEVERITY_INFO, f"{e.label}: fault cleared"
    if e.mode == "thrust_loss":
        what = f"thrust_loss {100.0 * e.magnitude:.0f} %"
    elif e.mode == "bias":
        what = f"bias {e.magnitude:g} counts"
    elif e.mode == "noise":
        what = f"noise {e.magnitude:g} x sigma"
    elif e.mode == "spike":
        what = f"spike {e.magnitude:g} counts"
    else:
        what = e.mode
    return M.MAV_SEVERITY_WARNING, f"{e.label}: {what} injected"


def _bits(mask: int) -> list[int]:
    out, i = [], 0
    while mask >> i:
        if (mask >> i) & 1:
            out.append(i)
        i += 1
    return out


def failsafe_text(f: FaultStatus, cfg) -> str:
    """Why the failsafe tripped and what it did."""
    reasons = []
    hold = cfg["failsafe.hold_time"]
    if f.failsafe & ALERT_ATTITUDE:
        reasons.append(f"attitude error {math.degrees(f.failsafe_attitude_error):.0f} deg > "
                       f"{cfg['failsafe.attitude_error_deg']:g} deg")
    if f.failsafe & ALERT_RATE:
        reasons.append(f"body rate {math.degrees(f.failsafe_rate):.0f} deg/s > {cfg['failsafe.rate_limit_deg_s']:g} deg/s")
    if f.failsafe & ALERT_ESTIMATE:
        reasons.append("attitude estimate invalid")
    action = "motors stopped, disarmed" if f.failsafe_action == "disarm" else "reported only, motors running"
    return f"loss of control: {', '.join(reasons)} for {hold:g} s; {action}"


class FaultReporter:
    """Diffs the rig's fault status chunk by chunk; see the module doc."""

    def __init__(self):
        self.seen_events = 0
        self.prev: FaultStatus | None = None
        self._signature = None
        self._plugin_failure = None

    def poll(self, rig) -> tuple[list[tuple[int, str]], bool]:
        """(STATUSTEXT (severity, text) pairs to broadcast, whether the failsafe state changed)."""
        signature = rig.fault_signature()
        if signature == self._signature:
            return [], False
        self._signature = signature
        out = []
        events = rig.fault_events(self.seen_events)
        self.seen_events += len(events)
        out.extend(injection_text(e) for e in events)
        f = rig.fault_status()
        p = self.prev
        self.prev = f
        if p is None:
            p = FaultStatus(imu_faults=f.imu_faults, cell_faults=f.cell_faults, motor_faults=f.motor_faults,
                            motor_thrust_loss=f.motor_thrust_loss, imu_flagged=(0, 0, 0), cells_flagged=0,
                            estimate_invalid=0, alerts=0, failsafe=0, failsafe_action=f.failsafe_action,
                            failsafe_time_s=math.nan, failsafe_attitude_error=0.0, failsafe_rate=0.0,
                            attitude_error=0.0, events=0)
        for m in range(len(f.imu_faults)):
            now = [KINDS[s] for s in range(3) if (f.imu_flagged[s] >> m) & 1]
            before = [KINDS[s] for s in range(3) if (p.imu_flagged[s] >> m) & 1]
            if now and not before:
                out.append((M.MAV_SEVERITY_WARNING, f"ensemble rejects IMU module {m} ({', '.join(now)})"))
            elif before and not now:
                out.append((M.MAV_SEVERITY_INFO, f"ensemble accepts IMU module {m} again"))
        for i in _bits(f.cells_flagged & ~p.cells_flagged):
            out.append((M.MAV_SEVERITY_WARNING, f"load cell {i + 1}: readings rejected by the guards"))
        for i in _bits(p.cells_flagged & ~f.cells_flagged):
            out.append((M.MAV_SEVERITY_INFO, f"load cell {i + 1}: readings accepted again"))
        att_bits = INVALID_GYRO | INVALID_ACCEL
        if f.estimate_invalid != p.estimate_invalid:
            bad = [KINDS[s] for s in range(3) if (f.estimate_invalid >> s) & 1]
            if f.estimate_invalid & att_bits:
                out.append((M.MAV_SEVERITY_CRITICAL, f"attitude estimate invalid: fused {', '.join(bad)} "
                                                     f"(majority lost or implausible)"))
            elif bad:
                out.append((M.MAV_SEVERITY_WARNING, f"heading estimate invalid: fused {', '.join(bad)}"))
            else:
                out.append((M.MAV_SEVERITY_INFO, "IMU estimate valid again"))
        changed = f.failsafe != p.failsafe
        if changed and f.failsafe:
            out.append((M.MAV_SEVERITY_CRITICAL, failsafe_text(f, rig.cfg)))
        elif changed:
            out.append((M.MAV_SEVERITY_INFO, "failsafe cleared (armed again)"))
        failure = getattr(rig, "plugin_failure", None)
        if failure is not self._plugin_failure:
            if failure is not None:
                out.append((M.MAV_SEVERITY_CRITICAL, plugin_failure_text(failure)))
            else:
                out.append((M.MAV_SEVERITY_INFO, f"controller {self._plugin_failure.plugin}: armed again, reset()"))
            self._plugin_failure = failure
            changed = True
        return out, changed


def plugin_failure_text(failure) -> str:
    """Why a controller plug-in stopped flying (a PluginError: plug-in, time, problem) and what the rig did."""
    return f"{failure}; motors stopped, disarmed; arm again to retry"
