"""The MAVLink standard modes microservice: AVAILABLE_MODES, CURRENT_MODE,
AVAILABLE_MODES_MONITOR and MAV_CMD_DO_SET_STANDARD_MODE
(https://mavlink.io/en/services/standard_modes.html).

* ``MAV_CMD_REQUEST_MESSAGE`` (AVAILABLE_MODES, param2 = mode index 1..N, 0 = all): one
  AVAILABLE_MODES per mode the rig flies (:meth:`FlightModes.available`), with PX4's
  custom_mode, the standard mode where there is one and PX4's name; an index out of range is
  DENIED. The rig's set of modes never changes, so AVAILABLE_MODES_MONITOR.seq stays 0.
* CURRENT_MODE: standard mode, custom_mode and intended custom mode (the same: the rig
  never falls back from a requested mode); sent on request and with every HEARTBEAT.
* ``MAV_CMD_DO_SET_STANDARD_MODE`` (param1 MAV_STANDARD_MODE): enters the PX4 mode that
  stands for it (POSITION_HOLD POSCTL, SAFE_RECOVERY AUTO.RTL, MISSION AUTO.MISSION, LAND
  AUTO.LAND, TAKEOFF AUTO.TAKEOFF), as DO_SET_MODE would; another value is UNSUPPORTED with
  a STATUSTEXT naming the supported ones.
"""

from __future__ import annotations

from protocol.dialect import mavlink as M
from rig_emulator.link.commands import modes as MD

ACCEPTED, DENIED, UNSUPPORTED = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED, M.MAV_RESULT_UNSUPPORTED
MONITOR_SEQ = 0


def available_modes(modes, index: int = 0) -> list:
    """AVAILABLE_MODES for mode ``index`` (1-based) or all (0); [] when out of range."""
    avail = modes.available()
    n = len(avail)
    picks = range(1, n + 1) if index == 0 else ([index] if 1 <= index <= n else [])
    out = []
    for i in picks:
        (main, sub), mode = avail[i - 1]
        out.append(M.MAVLink_available_modes_message(
            number_modes=n, mode_index=i, standard_mode=mode.standard, custom_mode=MD.custom_mode(main, sub),
            properties=0, mode_name=mode.label.encode("ascii")))
    return out


def current_mode(modes):
    return M.MAVLink_current_mode_message(standard_mode=modes.standard_mode, custom_mode=modes.custom_mode,
                                          intended_custom_mode=modes.custom_mode)


def monitor():
    return M.MAVLink_available_modes_monitor_message(seq=MONITOR_SEQ)


def request_available_modes(cmd, srv, channel):
    """REQUEST_MESSAGE(AVAILABLE_MODES, index): (result, messages)."""
    index = cmd.int_param(2) or 0
    out = available_modes(srv.modes, index)
    if not out:
        n = len(srv.modes.available())
        return DENIED, srv.statustext_messages(M.MAV_SEVERITY_WARNING, f"mode index {index} not in 1..{n}")
    return ACCEPTED, out


def set_standard_mode(cmd, srv, channel):
    std = cmd.int_param(1)
    for (main, sub), mode in srv.modes.available():
        if std is not None and mode.standard == std and std != MD.STD_NON_STANDARD:
            if not srv.modes.enter(main, sub, srv.rig):
                return DENIED, srv.statustext_messages(M.MAV_SEVERITY_WARNING, srv.modes.last_refusal)
            srv.heartbeat_pending = True
            return ACCEPTED, []
    names = ", ".join(M.enums["MAV_STANDARD_MODE"][m.standard].name.removeprefix("MAV_STANDARD_MODE_")
                      for _k, m in srv.modes.available() if m.standard)
    return UNSUPPORTED, srv.statustext_messages(
        M.MAV_SEVERITY_WARNING, f"standard mode {cmd.p(1)} not supported (supported: {names})")
