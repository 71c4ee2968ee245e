"""A pymavlink link to a vehicle: connect, find the vehicle, command it, request streams.

Connections are mavutil connection strings (``tcp:127.0.0.1:5760``, ``udpin:0.0.0.0:14550``,
``udpout:host:port``, ``/dev/ttyUSB0``, ...), opened in the hilms dialect over MAVLink 2 as
ground station (system 255, component MAV_COMP_ID_MISSIONPLANNER by default).

A link is a ground station's: it sends HEARTBEAT (MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID) once
every :data:`HEARTBEAT_PERIOD_S`, as every ground station does, so a vehicle's data-link-loss
failsafe (PX4's COM_DL_LOSS_T, the rig's ``failsafe.gcs_timeout``) never sees a scripted tool
as a lost ground station. The heartbeat goes out from the tool's own receive loop
(:meth:`Link.recv`, :meth:`Link.heartbeat_if_due` for loops that read the connection
themselves), whose waits are at most :data:`RECV_SLICE_S`: no thread shares the connection.
"""

from __future__ import annotations

import math
import time

from gcs_tools.errors import OperationError, UsageError
from gcs_tools.stale_acks import StaleAcks
from protocol.dialect import mavlink as M
from protocol.dialect import use_hilms_dialect

GCS_SYSID = 255
GCS_COMPID = M.MAV_COMP_ID_MISSIONPLANNER
HEARTBEAT_TIMEOUT_S = 10.0
COMMAND_TIMEOUT_S = 1.5
COMMAND_RETRIES = 3
HEARTBEAT_PERIOD_S = 1.0  # a ground station's HEARTBEAT rate (1 Hz)
RECV_SLICE_S = 0.25  # the longest single wait of a receive loop, so the heartbeat keeps its rate
NAN = math.nan
#: the clock the heartbeat period is judged on (wall time; a test may drive it)
heartbeat_clock = time.monotonic


class Link:
    """A connection to one vehicle (the first that sends a HEARTBEAT, or ``target_system``)."""

    def __init__(self, url: str, target_system: int | None = None, source_system: int = GCS_SYSID,
                 source_component: int = GCS_COMPID):
        use_hilms_dialect()
        from pymavlink import mavutil

        try:
            self.conn = mavutil.mavlink_connection(url, source_system=source_system,
                                                   source_component=source_component, autoreconnect=False)
        except (OSError, ValueError) as exc:
            raise OperationError(f"cannot open {url}: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - pymavlink raises bare Exceptions for bad device strings
            raise UsageError(f"cannot open {url}: {exc}") from None
        self.url = url
        self.target_system = target_system
        self.target_component = M.MAV_COMP_ID_AUTOPILOT1
        self.last_heartbeat = None
        self.stale_acks = StaleAcks()
        self.heartbeats_sent = 0
        self._next_heartbeat = -math.inf

    @property
    def mav(self):
        return self.conn.mav

    def close(self) -> None:
        self.conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def heartbeat_if_due(self) -> None:
        """Send the ground station's HEARTBEAT when :data:`HEARTBEAT_PERIOD_S` has passed since the last."""
        now = heartbeat_clock()
        if now < self._next_heartbeat:
            return
        due = self._next_heartbeat + HEARTBEAT_PERIOD_S
        self._next_heartbeat = due if due > now else now + HEARTBEAT_PERIOD_S  # behind (or the first): from now
        try:
            self.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, M.MAV_STATE_ACTIVE)
        except OSError as exc:
            raise OperationError(f"link {self.url} lost: {exc}") from None
        self.heartbeats_sent += 1

    def recv(self, types=None, timeout: float = 1.0, condition=None):
        """The next message of ``types`` from the vehicle satisfying ``condition`` (None on timeout);
        the ground station's HEARTBEAT goes out meanwhile when due."""
        deadline = time.monotonic() + timeout
        while True:
            self.heartbeat_if_due()
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            try:
                msg = self.conn.recv_match(type=types, blocking=True, timeout=min(left, RECV_SLICE_S))
            except OSError as exc:
                raise OperationError(f"link {self.url} lost: {exc}") from None
            if msg is None:
                continue
            if msg.get_type() == "HEARTBEAT" and msg.get_srcSystem() == self.target_system:
                self.last_heartbeat = msg
            if self.target_system is not None and msg.get_srcSystem() != self.target_system:
                continue
            if condition is None or condition(msg):
                return msg

    def wait_vehicle(self, timeout: float = HEARTBEAT_TIMEOUT_S):
        """Wait for the vehicle's HEARTBEAT; sets ``target_system``/``target_component``."""

        def is_vehicle(m):
            return m.type != M.MAV_TYPE_GCS and m.autopilot != M.MAV_AUTOPILOT_INVALID

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            # recv sends the ground station's HEARTBEAT: a vehicle serving UDP (udpin) learns of a
            # ground station only from what it sends
            msg = self.recv("HEARTBEAT", min(1.0, deadline - time.monotonic()))
            if msg is not None and is_vehicle(msg) and msg.system_status == M.MAV_STATE_BOOT:
                # a starting vehicle (the rig compiling its step loop: minutes on a cold cache) answers
                # commands only once it runs: wait for it while it keeps saying so
                deadline = max(deadline, time.monotonic() + timeout)
                continue
            if msg is not None and is_vehicle(msg):
                self.target_system = msg.get_srcSystem()
                self.target_component = msg.get_srcComponent()
                self.last_heartbeat = msg
                return msg
        raise OperationError(f"no vehicle HEARTBEAT on {self.url} within {timeout:g} s")

    def command(self, cmd: int, *params, timeout: float = COMMAND_TIMEOUT_S, retries: int = COMMAND_RETRIES):
        """COMMAND_LONG with the command protocol's retries; returns the COMMAND_ACK result."""
        p = list(params) + [NAN] * (7 - len(params))
        stale = self.stale_acks  # stale ACKs of earlier transmissions are not this command's answer
        for attempt in range(retries + 1):
            self.mav.command_long_send(self.target_system, self.target_component, cmd, attempt, *p)
            sent = time.monotonic()
            ack = self.recv("COMMAND_ACK", timeout, lambda m: m.command == cmd and stale.fresh(m))
            if ack is not None:
                stale.consumed(ack)
                if ack.result == M.MAV_RESULT_IN_PROGRESS:
                    ack = self.recv("COMMAND_ACK", 10 * timeout, lambda m: m.command == cmd and stale.fresh(m)
                                    and m.result != M.MAV_RESULT_IN_PROGRESS)
                    if ack is None:
                        break
                    stale.consumed(ack)
                if attempt > 0:
                    stale.absorb(self, cmd, sent + timeout)
                return ack.result
        name = M.enums["MAV_CMD"][cmd].name if cmd in M.enums["MAV_CMD"] else str(cmd)
        raise OperationError(f"{name}: no COMMAND_ACK after {retries + 1} attempts")

    def command_ok(self, cmd: int, *params, what: str = "") -> None:
        result = self.command(cmd, *params)
        if result != M.MAV_RESULT_ACCEPTED:
            name = M.enums["MAV_RESULT"][result].name if result in M.enums["MAV_RESULT"] else str(result)
            raise OperationError(f"{what or M.enums['MAV_CMD'][cmd].name} rejected: {name}")

    def is_armed(self) -> bool:
        hb = self.last_heartbeat
        return hb is not None and bool(hb.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)

    def arm(self) -> None:
        self.command_ok(M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0, what="arming")

    def set_message_rate(self, msg_id: int, hz: float) -> None:
        """MAV_CMD_SET_MESSAGE_INTERVAL (hz <= 0 stops the message)."""
        interval = -1.0 if hz <= 0 else 1e6 / hz
        self.command_ok(M.MAV_CMD_SET_MESSAGE_INTERVAL, float(msg_id), interval,
                        what=f"SET_MESSAGE_INTERVAL {msg_id} at {hz:g} Hz")

    def request_data_streams(self, hz: float) -> None:
        """The legacy REQUEST_DATA_STREAM for every stream group (no ACK in the protocol)."""
        self.mav.request_data_stream_send(self.target_system, self.target_component, M.MAV_DATA_STREAM_ALL,
                                          int(round(hz)), 1 if hz > 0 else 0)

    def home_position(self, timeout: float = COMMAND_TIMEOUT_S, attempts: int = COMMAND_RETRIES + 1):
        """The vehicle's HOME_POSITION, asked for with MAV_CMD_GET_HOME_POSITION.

        None when the vehicle refuses the command (it has no home); OperationError when neither
        HOME_POSITION nor a refusal arrives after ``attempts`` requests, so a lossy link fails
        clearly instead of giving a mission without its home. Each request is a new command
        (``confirmation`` 0): a vehicle answers a retry of a command it already acted on with
        the earlier ACK alone, without sending the message again.
        """
        cmd = M.MAV_CMD_GET_HOME_POSITION

        def answer():  # HOME_POSITION, or this command's ACK
            return self.recv(["HOME_POSITION", "COMMAND_ACK"], timeout,
                             lambda m: m.get_type() == "HOME_POSITION" or m.command == cmd)

        for _ in range(attempts):
            self.mav.command_long_send(self.target_system, self.target_component, cmd, 0, *([NAN] * 7))
            msg = answer()
            while msg is not None and msg.get_type() == "COMMAND_ACK":
                if msg.result not in (M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_IN_PROGRESS):
                    return None  # refused: the vehicle has no home to send
                msg = answer()  # accepted: the message follows the ACK
            if msg is not None:
                return msg
        raise OperationError(f"no HOME_POSITION from the vehicle after {attempts} MAV_CMD_GET_HOME_POSITION requests")


def message_id(name: str) -> int:
    """MAVLink message id of a message name (UsageError when unknown)."""
    cls = M.mavlink_map.get(getattr(M, f"MAVLINK_MSG_ID_{name.upper()}", -1))
    if cls is None:
        raise UsageError(f"unknown MAVLink message {name!r}")
    return cls.id


def open_link(args) -> Link:
    """A :class:`Link` to ``args.connection`` whose vehicle (``args.sysid``, or the first heard)
    has been heard within ``args.heartbeat_timeout`` seconds: what every ``rig-gcs`` subcommand
    that talks to a vehicle opens first."""
    link = Link(args.connection, target_system=args.sysid)
    link.wait_vehicle(args.heartbeat_timeout)
    return link
