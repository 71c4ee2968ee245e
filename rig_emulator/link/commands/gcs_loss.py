"""Loss of the ground station: PX4's data-link-loss failsafe (COM_DL_LOSS_T, NAV_DLL_ACT).

A ground station is a peer whose HEARTBEAT says MAV_TYPE_GCS. Once one has been heard, the
link is *lost* when no GCS HEARTBEAT has arrived for ``failsafe.gcs_timeout`` seconds of
wall-clock time (heartbeats are sent by the wall clock, whatever the rig's speed-up),
reported once. Then, as soon as the rig is armed in a mode that needs a ground station -
POSCTL, AUTO.LOITER, STABILIZED: modes that wait for the operator's next command - the
``failsafe.gcs_action`` runs, once per loss: ``hold``
(AUTO.LOITER), ``return`` (AUTO.RTL), ``land`` (AUTO.LAND) or ``disarm``; ``none`` only
reports. Missions, take-off, return and landing carry on (they need no one). A GCS
HEARTBEAT again ends the loss (reported); the rig stays in the mode the action chose.
"""

from __future__ import annotations

import time

from protocol.dialect import mavlink as M
from rig_emulator.link.commands import modes as MD

NEEDS_GCS = {(MD.POSCTL, 0), (MD.AUTO, MD.AUTO_LOITER), (MD.STABILIZED, 0)}
ACTION_MODES = {"hold": (MD.AUTO, MD.AUTO_LOITER), "return": (MD.AUTO, MD.AUTO_RTL), "land": (MD.AUTO, MD.AUTO_LAND)}


class GcsLoss:
    def __init__(self, clock=time.monotonic):
        self.clock = clock
        self.last_heartbeat: float | None = None
        self.lost = False
        self.acted = False  # the action ran during this loss
        self.trips = 0

    def heard(self, msg) -> bool:
        """A HEARTBEAT arrived; True when it ends a loss."""
        if msg.type != M.MAV_TYPE_GCS:
            return False
        self.last_heartbeat = self.clock()
        if self.lost:
            self.lost = self.acted = False
            return True
        return False

    def check(self, srv) -> None:
        """Call every loop: report a loss once, and run the action once while the rig is armed
        in a mode that needs a ground station during the loss."""
        if self.last_heartbeat is None or self.acted:
            return
        cfg = srv.rig.cfg
        if not self.lost:
            silent = self.clock() - self.last_heartbeat
            if silent <= cfg["failsafe.gcs_timeout"]:
                return
            self.lost = True
            srv.statustext(None, M.MAV_SEVERITY_WARNING, f"ground station lost ({silent:.0f} s without a GCS heartbeat)")
        action = cfg["failsafe.gcs_action"]
        if action == "none" or not srv.rig.armed or (srv.modes.main, srv.modes.sub) not in NEEDS_GCS:
            return
        self.acted = True
        self.trips += 1
        srv.statustext(None, M.MAV_SEVERITY_CRITICAL, f"ground station lost in {srv.modes.name}: failsafe {action}")
        if action == "disarm":
            srv.flight.arm(False)
        else:
            srv.modes.enter(*ACTION_MODES[action], srv.rig)
        srv.heartbeat_pending = True
