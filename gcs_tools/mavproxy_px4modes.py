"""A MAVProxy module that makes ``mode NAME`` (and a bare mode name typed as a command) work on
a PX4 vehicle such as the rig.

Why it is needed: MAVProxy 1.8.75's ``mode`` command looks the name up in
``master.mode_mapping()``, which for a HEARTBEAT with MAV_AUTOPILOT_PX4 is pymavlink's
``px4_map`` of (base_mode, main_mode, sub_mode) triples, and hands the triple to
``master.set_mode``. pymavlink 2.4.50's ``set_mode_px4`` only unpacks names (``str``), so the
triple reaches ``command_long_send`` as param1 and packing fails (``struct.error: required
argument is not a float``): nothing is sent. Nothing a vehicle sends changes that path (it
is taken for every PX4 autopilot), so the fix has to be on the client side. This module
sends the same triple as MAV_CMD_DO_SET_MODE (base_mode, custom main mode, custom sub mode),
exactly what ``long DO_SET_MODE <base> <main> <sub>`` sends by hand.

Use (MAVProxy installed in the environment where hilms-sil is installed)::

    mavproxy.py --master=tcp:127.0.0.1:5760 --load-module=gcs_tools.mavproxy_px4modes
    # or, inside MAVProxy:  module load gcs_tools.mavproxy_px4modes

Then ``mode POSCTL``, ``mode LOITER``, ``posctl``, ``mode SYSID`` (the rig's identification flight),
``mode 50593792`` (a PX4 custom_mode number) work.
For any other autopilot the ``mode`` command is MAVProxy's own. Imported only by MAVProxy.
"""

from __future__ import annotations

from MAVProxy.modules.lib import mp_module
from pymavlink import mavutil

from protocol.px4_custom_mode import RIG_MODES, split_custom_mode


def px4_mode_triple(arg: str):
    """(base_mode, main_mode, sub_mode) of a PX4 mode name (pymavlink's px4_map, any case), of a mode the
    rig adds (``SYSID``, :data:`protocol.px4_custom_mode.RIG_MODES`) or of a PX4 custom_mode number (main mode in bits 16-23, sub mode in bits 24-31); None if neither."""
    name = arg.upper()
    if name in mavutil.px4_map:
        return tuple(int(v) for v in mavutil.px4_map[name])
    if name in RIG_MODES:
        return (int(mavutil.mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), *RIG_MODES[name])
    if arg.isdigit():
        return (int(mavutil.mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), *split_custom_mode(int(arg)))
    return None


class PX4ModesModule(mp_module.MPModule):
    def __init__(self, mpstate):
        super().__init__(mpstate, "px4modes", "PX4 mode names for the mode command")
        self._theirs = None  # MAVProxy's own mode command, used for non-PX4 vehicles
        self._claim()

    def _claim(self) -> None:
        """Make ``mode`` ours; MAVProxy's mode module may register it after us (``--load-module``
        modules load before the standard ones), so this is repeated from the idle task."""
        current = self.mpstate.command_map.get("mode")
        if current is not None and current[0] == self.cmd_mode:
            return
        if current is not None:
            self._theirs = current[0]
        self.add_command("mode", self.cmd_mode, "mode change (PX4 names sent as DO_SET_MODE)", ["(MODE)"])

    def idle_task(self):
        self._claim()

    def _is_px4(self) -> bool:
        return self.master is not None and self.master.field("HEARTBEAT", "autopilot", None) == \
            mavutil.mavlink.MAV_AUTOPILOT_PX4

    def _send(self, triple) -> None:
        base, main, sub = triple
        self.master.mav.command_long_send(self.target_system, self.target_component,
                                          mavutil.mavlink.MAV_CMD_DO_SET_MODE, 0, base, main, sub, 0, 0, 0, 0)

    def cmd_mode(self, args):
        if not self._is_px4():
            if self._theirs is not None:
                return self._theirs(args)
            print("px4modes: no PX4 vehicle (HEARTBEAT autopilot is not MAV_AUTOPILOT_PX4)")
            return
        if len(args) != 1:
            print("Available modes: ", ", ".join(mavutil.px4_map))
            return
        triple = px4_mode_triple(args[0])
        if triple is None:
            print("Unknown mode %s: " % args[0])
            return
        self._send(triple)

    def unknown_command(self, args):
        """A PX4 mode name typed as a command (``posctl``), as MAVProxy's mode module offers."""
        if not args or not self._is_px4() or args[0].upper() not in mavutil.px4_map:
            return False
        self._send(px4_mode_triple(args[0]))
        return True


def init(mpstate):
    return PX4ModesModule(mpstate)
