"""The rig's link and loop counters as NAMED_VALUE_INT messages, sent on request.

``MAV_CMD_REQUEST_MESSAGE`` with param1 = NAMED_VALUE_INT (252) is answered with one
NAMED_VALUE_INT per counter, ``time_boot_ms`` the simulated time, in this order:

==============  ==============================================================================
name            value
==============  ==============================================================================
RX_MSGS         messages decoded (:class:`~rig_emulator.link.endpoints.counters.LinkCounters` ``received``)
TX_MSGS         messages sent
RX_BYTES        bytes read from every peer
RX_READS        reads (UDP datagrams, TCP reads)
BAD_BYTES       bytes dropped by the parser (garbage, bad frames, truncated datagrams)
COMMANDS        COMMAND_LONG/INT received
DROPPED         messages and byte runs dropped, all reasons
D_...           dropped for one reason (:data:`DROP_NAMES`); D_OTHER: reasons not listed
STEPS           physics steps run (``sim.physics_rate_hz`` a simulated second)
CTRL_STEPS      control updates run (every ``physics_rate / control_rate`` steps, from step 0)
PACE_RESET      times the pacing gave up catching up with wall-clock time x speed-up
LAG_MS          simulated milliseconds of lag given up then (control periods missed in real time)
==============  ==============================================================================

Values saturate at the int32 range. :func:`read_link_status` is the client side.
"""

from __future__ import annotations

import time

from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry import units as U

DROP_NAMES = {
    "bad_crc": "D_BADCRC", "bad_prefix": "D_PREFIX", "bad_data": "D_BADDATA", "truncated": "D_TRUNC",
    "unknown_id": "D_UNKNOWN", "own_echo": "D_ECHO", "other_system": "D_OTHSYS", "other_component": "D_OTHCOMP",
    "unhandled": "D_UNHANDLD", "invalid": "D_INVALID", "handler_error": "D_HANDLER", "peer_limit": "D_PEERS",
    "tx_overflow": "D_TXFULL", "unsupported_frame": "D_FRAME", "unsupported_setpoint": "D_SETPOINT",
    "mission_type": "D_MISTYPE", "unexpected_mission_item": "D_MISITEM", "duplicate_mission_item": "D_MISDUP",
    "duplicate_command": "D_CMDDUP", "unsigned": "D_UNSIGNED", "bad_signature": "D_BADSIG", "replay": "D_REPLAY",
    "stale_timestamp": "D_STALE",
}
OTHER = "D_OTHER"


def control_divider(cfg) -> int:
    return max(1, int(round(cfg["sim.physics_rate_hz"] / cfg["sim.control_rate_hz"])))


def status_values(counters, cfg) -> dict[str, int]:
    """Every counter by its NAMED_VALUE_INT name."""
    div = control_divider(cfg)
    dropped = dict(counters.dropped)
    out = {"RX_MSGS": counters.received, "TX_MSGS": counters.sent, "RX_BYTES": counters.rx_bytes,
           "RX_READS": counters.rx_reads, "BAD_BYTES": counters.bad_bytes, "COMMANDS": counters.commands,
           "DROPPED": sum(dropped.values())}
    for reason, name in DROP_NAMES.items():
        out[name] = dropped.get(reason, 0)
    out[OTHER] = sum(n for reason, n in dropped.items() if reason not in DROP_NAMES)
    out["STEPS"] = counters.steps
    out["CTRL_STEPS"] = -(-counters.steps // div)  # updates at steps 0, div, 2 div, ... before `steps`
    out["PACE_RESET"] = counters.pacing_resets
    out["LAG_MS"] = int(round(counters.lag_dropped_s * 1000.0))
    return out


def link_status(snap, ctx) -> list:
    """The NAMED_VALUE_INT messages (an ON_REQUEST builder: ``(snapshot, ctx)``)."""
    t = U.time_boot_ms(snap.stamp_us)
    return [M.MAVLink_named_value_int_message(time_boot_ms=t, name=name.encode("ascii"),
                                              value=U.clamp_int(value, *U.INT32))
            for name, value in status_values(ctx.counters, ctx.cfg).items()]


def read_link_status(conn, target=(1, 1), timeout: float = 5.0) -> dict | None:
    """Ask a rig for its counters over a pymavlink connection: {name: value, "time_s": sim time}.

    Returns None when no complete answer arrived within ``timeout`` seconds."""
    names = set(status_values_names())
    conn.mav.command_long_send(target[0], target[1], M.MAV_CMD_REQUEST_MESSAGE, 0,
                               float(M.MAVLINK_MSG_ID_NAMED_VALUE_INT), 0, 0, 0, 0, 0, 0)
    got: dict = {}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not names <= set(got):
        msg = conn.recv_match(type="NAMED_VALUE_INT", blocking=True, timeout=0.2)
        if msg is None or msg.get_srcSystem() != target[0]:
            continue
        name = msg.name if isinstance(msg.name, str) else msg.name.decode("ascii", "replace")
        if name == "RX_MSGS":
            got = {"time_s": msg.time_boot_ms / 1000.0}  # a new answer starts
        if got:
            got[name] = msg.value
    return got if names <= set(got) else None


def status_values_names() -> list[str]:
    return ["RX_MSGS", "TX_MSGS", "RX_BYTES", "RX_READS", "BAD_BYTES", "COMMANDS", "DROPPED",
            *DROP_NAMES.values(), OTHER, "STEPS", "CTRL_STEPS", "PACE_RESET", "LAG_MS"]
