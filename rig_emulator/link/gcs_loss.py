"""Loss of the ground station: PX4's data-link-loss failsafe (COM_DL_LOSS_T, NAV_DLL_ACT).

A ground station is a peer whose HEARTBEAT says MAV_TYPE_GCS. Once one has been heard, the
link is *lost* when no GCS HEARTBEAT has arrived for ``failsafe.gcs_timeout`` seconds of
wall-clock time (heartbeats are sent by the wall clock, whatever the rig's speed-up). If the
rig is armed in a mode that needs a ground station - POSCTL, AUTO.LOITER, STABILIZED: modes
that wait for the operator's next command - the ``failsafe.gcs_action`` runs once: ``hold``
(AUTO.LOITER), ``return`` (AUTO.RTL), ``land`` (AUTO.LAND) or ``disarm``; ``none`` only
reports. Missions, take-off, return and landing carry on (they need no one). A GCS
HEARTBEAT again ends the loss (reported); the rig stays in the mode the action chose.
"""

from __future__ import annotations

import time

from protocol.dialect import mavlink as M
from rig_emulator.link import modes as MD

NEEDS_GCS = {(MD.POSCTL, 0), (MD.AUTO, MD.AUTO_LOITER), (MD.STABILIZED, 0)}
ACTION_MODES = {"hold": (MD.AUTO, MD.AUTO_LOITER), "return": (MD.AUTO, MD.AUTO_RTL), "land": (MD.AUTO, MD.AUTO_LAND)}


class GcsLoss:
    def __init__(self, clock=time.monotonic):
        self.clock = clock
        self.last_heartbeat: float | None = None
        self.lost = False
        self.trips = 0

    def heard(self, msg) -> bool:
        """A HEARTBEAT arrived; True when it ends a loss."""
        if msg.type != M.MAV_TYPE_GCS:
            return False
        self.last_heartbeat = self.clock()
        if self.lost:
            self.lost = False
            return True
        return False

    def check(self, srv) -> None:
        """Trip the failsafe when the ground station has been silent too long (call every loop)."""
        if self.last_heartbeat is None or self.lost:
            return
        cfg = srv.rig.cfg
        silent = self.clock() - self.last_heartbeat
        if silent <= cfg["failsafe.gcs_timeout"]:
            return
        self.lost = True
        action = cfg["failsafe.gcs_action"]
        snap = srv.snapshot()
        mode = (srv.modes.main, srv.modes.sub)
        why_not = ("disarmed" if not snap.armed else "failsafe.gcs_action none" if action == "none"
                   else None if mode in NEEDS_GCS else f"{srv.modes.name} needs no ground station")
        if why_not is not None:
            srv.statustext(None, M.MAV_SEVERITY_WARNING,
                           f"ground station lost ({silent:.0f} s without a GCS heartbeat): no action, {why_not}")
            return
        self.trips += 1
        srv.statustext(None, M.MAV_SEVERITY_CRITICAL, f"ground station lost ({silent:.0f} s without a GCS heartbeat): "
                       f"failsafe {action}")
        if action == "disarm":
            srv.flight.arm(False)
        else:
            srv.modes.enter(*ACTION_MODES[action], srv.rig)
        srv.heartbeat_pending = True
