"""The MAVLink mission protocol on the rig (vehicle side), mission_type MISSION.

Upload: MISSION_COUNT -> the rig requests each item (MISSION_REQUEST_INT, or MISSION_REQUEST
to a peer that last used the float messages) -> MISSION_ITEM_INT / MISSION_ITEM -> ...
-> MISSION_ACK. Items may arrive duplicated, out of order or pipelined ahead of the
requests: each item not held yet is validated and kept, and the lowest missing one is
requested next. The mission is replaced only when every item is in and valid, so an upload
that fails, is cancelled (MISSION_ACK from the peer) or times out leaves the previous
mission exactly as it was. Timeouts follow PX4's figures: an item not received within
:data:`RETRY_S` is requested again; an upload without progress for :data:`GIVE_UP_S` is
abandoned with MISSION_ACK MAV_MISSION_OPERATION_CANCELLED. One upload at a time: another
peer's MISSION_COUNT meanwhile gets MAV_MISSION_DENIED; the same peer's MISSION_COUNT with
the same count is a retry (the lowest missing item is requested again), with another count
it restarts the upload. An item of an upload that already completed is answered with its
MISSION_ACK again (the peer missed it).

Results (MISSION_ACK.type): ACCEPTED; NO_SPACE (more than :data:`MAX_ITEMS`);
INVALID_SEQUENCE (an item beyond the announced count, a request beyond the mission);
UNSUPPORTED / UNSUPPORTED_FRAME / INVALID_PARAMx for an item the rig cannot fly
(:func:`protocol.mission_items.validate_item`, reason also in a STATUSTEXT) or, once every
item is in, for an item outside the geofence, under the ground or ending a leg longer than
MIS_DIST_WPS (:mod:`protocol.mission_checks`, the field the result names); DENIED;
OPERATION_CANCELLED; ERROR when the new (or cleared) mission cannot be stored in the
state directory (the previous one stays). MISSION_COUNT 0 clears the mission.

Download: MISSION_REQUEST_LIST -> MISSION_COUNT -> MISSION_REQUEST_INT (answered with
MISSION_ITEM_INT) or MISSION_REQUEST (answered with MISSION_ITEM) -> ... -> MISSION_ACK.
The rig answers every request as it comes (retries and pipelined requests included) from
the mission as it was at the peer's MISSION_REQUEST_LIST.

Fence and rally points: the rig has none. Downloads get MISSION_COUNT 0, uploads of one or
more items MAV_MISSION_UNSUPPORTED, empty uploads and MISSION_CLEAR_ALL are ACCEPTED.
MISSION_CLEAR_ALL with MAV_MISSION_TYPE_ALL clears the mission.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from protocol.dialect import mavlink as M
from protocol.mission_checks import check_plan
from protocol.mission_items import (item_from_message, item_to_float_message, item_to_int_message, mission_plan,
                                    validate_item)
from rig_emulator.link.commands.flight_monitors import mission_limits
from rig_emulator.link.state.directory import StateWriteError

RETRY_S = 0.25  # PX4: MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT
GIVE_UP_S = 5.0  # PX4: MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT
MAX_ITEMS = 10_000
MISSION = M.MAV_MISSION_TYPE_MISSION


@dataclass
class _Upload:
    channel: object
    peer: tuple  # (sysid, compid) of the uploader
    count: int
    int_mode: bool
    items: dict = field(default_factory=dict)
    last_progress: float = 0.0
    last_request: float = 0.0


class MissionTransfer:
    def __init__(self, server, executor):
        self.srv = server
        self.executor = executor
        self.upload: _Upload | None = None
        self._completed: dict = {}  # channel -> count of its last completed upload
        self._download: dict = {}  # channel -> items snapshot at MISSION_REQUEST_LIST
        self._int_mode: dict = {}  # channel -> True when the peer last used the *_INT messages
        self.uploads_done = 0
        self.uploads_failed = 0

    # --- helpers --------------------------------------------------------------------------------
    @staticmethod
    def _peer(msg) -> tuple:
        return msg.get_srcSystem(), msg.get_srcComponent()

    def _ack(self, channel, peer, result: int, mission_type: int = MISSION) -> None:
        channel.send(M.MAVLink_mission_ack_message(target_system=peer[0], target_component=peer[1], type=result,
                                                   mission_type=mission_type))

    def _fail(self, result: int, reason: str) -> None:
        up = self.upload
        self.upload = None
        self.uploads_failed += 1
        self._ack(up.channel, up.peer, result)
        self.srv.statustext(None, M.MAV_SEVERITY_WARNING, f"mission upload failed: {reason}")

    def _request_missing(self, now: float) -> None:
        up = self.upload
        seq = next(s for s in range(up.count) if s not in up.items)
        if up.int_mode:
            msg = M.MAVLink_mission_request_int_message(target_system=up.peer[0], target_component=up.peer[1],
                                                        seq=seq, mission_type=MISSION)
        else:
            msg = M.MAVLink_mission_request_message(target_system=up.peer[0], target_component=up.peer[1],
                                                    seq=seq, mission_type=MISSION)
        up.channel.send(msg)
        up.last_request = now

    # --- upload ------------------------------------------------------------------------------------
    def count(self, msg, channel) -> None:
        peer, mtype, n = self._peer(msg), msg.mission_type, msg.count
        if mtype != MISSION:
            self._ack(channel, peer, M.MAV_MISSION_ACCEPTED if n == 0 else M.MAV_MISSION_UNSUPPORTED, mtype)
            return
        now = time.monotonic()
        up = self.upload
        if up is not None and up.channel is not channel:
            if now - up.last_progress < GIVE_UP_S:
                self._ack(channel, peer, M.MAV_MISSION_DENIED)
                self.srv.statustext(None, M.MAV_SEVERITY_WARNING,
                                    "mission upload denied: another upload is in progress")
                return
            self._fail(M.MAV_MISSION_OPERATION_CANCELLED, "timed out")
            up = None
        if up is not None and up.count == n:
            self._request_missing(now)  # the peer missed our request: a retry, not a restart
            return
        self.upload = None
        self._completed.pop(channel, None)
        if n == 0:
            if not self._clear(channel, peer, MISSION):
                return
            self.uploads_done += 1
            self._ack(channel, peer, M.MAV_MISSION_ACCEPTED)
            return
        if n > MAX_ITEMS:
            self._ack(channel, peer, M.MAV_MISSION_NO_SPACE)
            self.srv.statustext(None, M.MAV_SEVERITY_WARNING, f"mission upload refused: {n} items, at most {MAX_ITEMS}")
            return
        self.upload = _Upload(channel=channel, peer=peer, count=n, int_mode=self._int_mode.get(channel, True),
                              last_progress=now)
        self._request_missing(now)

    def item(self, msg, channel) -> None:
        is_int = msg.get_type() == "MISSION_ITEM_INT"
        self._int_mode[channel] = is_int
        if msg.mission_type != MISSION:
            self.srv.counters.drop("mission_type")
            return
        up = self.upload
        if up is None or up.channel is not channel:
            done = self._completed.get(channel)
            if done is not None and msg.seq < done:
                self._ack(channel, self._peer(msg), M.MAV_MISSION_ACCEPTED)  # our ACK was lost
            else:
                self.srv.counters.drop("unexpected_mission_item")
            return
        up.int_mode = is_int
        if msg.seq >= up.count:
            self._fail(M.MAV_MISSION_INVALID_SEQUENCE, f"item {msg.seq} beyond the announced {up.count} items")
            return
        if msg.seq in up.items:
            self.srv.counters.drop("duplicate_mission_item")
            return
        item = item_from_message(msg)
        result, reason = validate_item(item, self.srv.ctx.home)
        if result != M.MAV_MISSION_ACCEPTED:
            self._fail(result, reason)
            return
        now = time.monotonic()
        up.items[msg.seq] = item
        up.last_progress = now
        if len(up.items) < up.count:
            self._request_missing(now)
            return
        items = [up.items[i] for i in range(up.count)]
        result, reason = self._plausible(items)
        if result != M.MAV_MISSION_ACCEPTED:
            self._fail(result, reason)
            return
        try:
            self.executor.replace(items)
        except StateWriteError as exc:
            self._fail(M.MAV_MISSION_ERROR, str(exc))
            return
        except ValueError as exc:
            self._fail(M.MAV_MISSION_INVALID, str(exc))
            return
        self.upload = None
        self.uploads_done += 1
        self._completed[channel] = up.count
        self._ack(channel, up.peer, M.MAV_MISSION_ACCEPTED)

    def _plausible(self, items) -> tuple[int, str]:
        """The whole-mission checks of :mod:`protocol.mission_checks` (fence, ground, leg length)."""
        cfg = self.srv.rig.cfg
        try:
            plan = mission_plan(items, self.srv.ctx.home, bool(cfg["mission.item0_home"]))
        except ValueError as exc:
            return M.MAV_MISSION_INVALID, str(exc)
        return check_plan(plan, mission_limits(cfg))

    def peer_ack(self, msg, channel) -> None:
        """MISSION_ACK from a peer: the end of its download, or its cancellation of our upload."""
        self._download.pop(channel, None)
        up = self.upload
        if (up is not None and up.channel is channel and msg.mission_type == MISSION
                and msg.type != M.MAV_MISSION_ACCEPTED):
            self.upload = None
            self.uploads_failed += 1
            self.srv.statustext(channel, M.MAV_SEVERITY_INFO, "mission upload cancelled by the ground station")

    def tick(self, now: float) -> None:
        """Retries and the give-up timeout of the upload in progress (wall-clock seconds)."""
        if len(self._int_mode) > len(self.srv.channels):
            live = set(map(id, self.srv.channels.values()))
            for table in (self._int_mode, self._download, self._completed):
                for ch in [c for c in table if id(c) not in live]:
                    del table[ch]
        up = self.upload
        if up is None:
            return
        if now - up.last_progress > GIVE_UP_S:
            self._fail(M.MAV_MISSION_OPERATION_CANCELLED, f"no item for {GIVE_UP_S:g} s")
        elif now - up.last_request >= RETRY_S:
            self._request_missing(now)

    # --- download ------------------------------------------------------------------------------------
    def request_list(self, msg, channel) -> None:
        peer, mtype = self._peer(msg), msg.mission_type
        if mtype == MISSION:
            self._download[channel] = self.executor.items
            n = len(self.executor.items)
        elif mtype in (M.MAV_MISSION_TYPE_FENCE, M.MAV_MISSION_TYPE_RALLY):
            n = 0
        else:
            self._ack(channel, peer, M.MAV_MISSION_UNSUPPORTED, mtype)
            return
        channel.send(M.MAVLink_mission_count_message(target_system=peer[0], target_component=peer[1], count=n,
                                                     mission_type=mtype))

    def request(self, msg, channel) -> None:
        is_int = msg.get_type() == "MISSION_REQUEST_INT"
        self._int_mode[channel] = is_int
        peer, mtype = self._peer(msg), msg.mission_type
        if mtype != MISSION:
            self._ack(channel, peer, M.MAV_MISSION_INVALID_SEQUENCE, mtype)
            return
        items = self._download.get(channel, self.executor.items)
        if not 0 <= msg.seq < len(items):
            self._ack(channel, peer, M.MAV_MISSION_INVALID_SEQUENCE)
            return
        encode = item_to_int_message if is_int else item_to_float_message
        channel.send(encode(items[msg.seq], peer[0], peer[1]))

    # --- clear, set current ------------------------------------------------------------------------------
    def clear_all(self, msg, channel) -> None:
        peer, mtype = self._peer(msg), msg.mission_type
        if mtype in (MISSION, M.MAV_MISSION_TYPE_ALL):
            if not self._clear(channel, peer, mtype):
                return
        elif mtype not in (M.MAV_MISSION_TYPE_FENCE, M.MAV_MISSION_TYPE_RALLY):
            self._ack(channel, peer, M.MAV_MISSION_UNSUPPORTED, mtype)
            return
        self._ack(channel, peer, M.MAV_MISSION_ACCEPTED, mtype)

    def _clear(self, channel, peer, mtype: int) -> bool:
        """Clear the mission; False (answered with MISSION_ACK ERROR) when that cannot be stored."""
        try:
            self.executor.clear()
        except StateWriteError as exc:
            self._ack(channel, peer, M.MAV_MISSION_ERROR, mtype)
            self.srv.statustext(None, M.MAV_SEVERITY_ERROR, f"mission not cleared: {exc}")
            return False
        return True

    def set_current(self, msg, channel) -> None:
        result, follow = self.executor.set_current(msg.seq)
        self.srv.send_follow(channel, follow)
        channel.send(self.executor.current_message())

    # --- registration ------------------------------------------------------------------------------------
    def handlers(self) -> dict:
        return {
            "MISSION_COUNT": self.count,
            "MISSION_ITEM": self.item,
            "MISSION_ITEM_INT": self.item,
            "MISSION_REQUEST_LIST": self.request_list,
            "MISSION_REQUEST": self.request,
            "MISSION_REQUEST_INT": self.request,
            "MISSION_ACK": self.peer_ack,
            "MISSION_CLEAR_ALL": self.clear_all,
            "MISSION_SET_CURRENT": self.set_current,
        }
