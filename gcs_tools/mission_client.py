"""The MAVLink mission protocol, ground side: upload, download, clear (mission type MISSION).

Follows https://mavlink.io/en/services/mission.html with the timeouts and retries ground
stations use (QGroundControl: 1.5 s, 5 retries):

* **upload**: MISSION_COUNT -> the vehicle requests each item (MISSION_REQUEST_INT, or the
  deprecated MISSION_REQUEST, answered with MISSION_ITEM) -> MISSION_ITEM_INT ... -> the
  vehicle's MISSION_ACK. Without a request within the timeout the last message (the count,
  or the last item sent) is sent again; re-requests of an earlier item are answered.
* **download**: MISSION_REQUEST_LIST -> MISSION_COUNT -> MISSION_REQUEST_INT per item ->
  MISSION_ITEM_INT (an item with the wrong sequence number is ignored and re-requested) ->
  MISSION_ACK(ACCEPTED) to the vehicle. The home position comes from HOME_POSITION.
* **clear**: MISSION_CLEAR_ALL -> MISSION_ACK.

Any MISSION_ACK with an error ends the transfer with that result. Failures raise
:class:`~gcs_tools.errors.OperationError`.

MAVLink <-> item conversion is the rig's own (:mod:`protocol.mission_items`: x/y as int32,
degrees x 1e7 in global frames, metres x 1e4 in local frames); params and z are float32,
read back as the shortest decimal of their float32 value (:func:`protocol.mission_files.f32`),
so file -> vehicle -> file is exact.
"""

from __future__ import annotations

import time

from gcs_tools.errors import OperationError
from gcs_tools.link import Link
from protocol.dialect import mavlink as M
from protocol import mission_items as MI
from protocol.mission_files import HOME_ALT_SCALE, HOME_LATLON_SCALE, Mission, MissionItem, f32

TIMEOUT_S = 1.5
RETRIES = 5
MISSION = M.MAV_MISSION_TYPE_MISSION


def result_name(code: int) -> str:
    e = M.enums["MAV_MISSION_RESULT"].get(code)
    return e.name if e is not None else str(code)


def to_wire(item: MissionItem, seq: int) -> MI.MissionItem:
    """The shared MAVLink item (:mod:`protocol.mission_items`) of a file item."""
    p1, p2, p3, p4 = item.params
    return MI.MissionItem(seq=seq, frame=item.frame, command=item.command, current=int(item.current),
                          autocontinue=int(item.autocontinue), param1=p1, param2=p2, param3=p3, param4=p4,
                          x=item.x, y=item.y, z=item.z, mission_type=MISSION)


def item_from_message(msg) -> MissionItem:
    """A file item from MISSION_ITEM_INT / MISSION_ITEM (float fields as their float32 decimal)."""
    w = MI.item_from_message(msg)
    return MissionItem(int(w.command), int(w.frame), tuple(f32(p) for p in (w.param1, w.param2, w.param3, w.param4)),
                       w.x, w.y, f32(w.z), bool(w.autocontinue), bool(w.current))


def _mission_msg(msg) -> bool:
    return getattr(msg, "mission_type", MISSION) == MISSION


def upload(link: Link, mission: Mission, timeout: float = TIMEOUT_S, retries: int = RETRIES, progress=None) -> None:
    """Upload ``mission`` (every item, item 0 included) to the vehicle."""
    target = (link.target_system, link.target_component)
    items = mission.items
    n = len(items)
    last_sent = M.MAVLink_mission_count_message(target_system=target[0], target_component=target[1], count=n,
                                                mission_type=MISSION)
    link.mav.send(last_sent)
    tries = 0
    highest = -1
    types = ["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"]
    while True:
        msg = link.recv(types, timeout, _mission_msg)
        if msg is None:
            tries += 1
            if tries > retries:
                stage = "MISSION_COUNT" if highest < 0 else f"item {highest}"
                raise OperationError(f"mission upload: no answer from the vehicle after {stage} "
                                     f"({retries} retries, {timeout:g} s each)")
            link.mav.send(last_sent)
            continue
        kind = msg.get_type()
        if kind == "MISSION_ACK":
            if msg.type != M.MAV_MISSION_ACCEPTED:
                raise OperationError(f"mission upload rejected by the vehicle: {result_name(msg.type)}")
            if highest != n - 1:
                raise OperationError(f"mission upload: vehicle acknowledged after {highest + 1} of {n} items")
            return
        seq = msg.seq
        if not 0 <= seq < n:
            raise OperationError(f"mission upload: vehicle requested item {seq} of a {n}-item mission")
        if seq > highest + 1:
            continue  # out of order: wait for the vehicle to request the right one (or time out)
        tries = 0
        build = MI.item_to_int_message if kind == "MISSION_REQUEST_INT" else MI.item_to_float_message
        last_sent = build(to_wire(items[seq], seq), target[0], target[1])
        link.mav.send(last_sent)
        highest = max(highest, seq)
        if progress is not None:
            progress(seq, n)


def download(link: Link, timeout: float = TIMEOUT_S, retries: int = RETRIES, progress=None) -> Mission:
    """Download the vehicle's mission; the home position is its HOME_POSITION (None if it refuses to send one)."""
    target = (link.target_system, link.target_component)

    def request_list():
        link.mav.mission_request_list_send(target[0], target[1], MISSION)

    count_msg = _ask(link, request_list, "MISSION_COUNT", timeout, retries, "MISSION_REQUEST_LIST")
    n = count_msg.count
    items = []
    for seq in range(n):
        def request_item(seq=seq):
            link.mav.mission_request_int_send(target[0], target[1], seq, MISSION)

        msg = _ask(link, request_item, ["MISSION_ITEM_INT", "MISSION_ITEM"], timeout, retries,
                   f"MISSION_REQUEST_INT {seq}", lambda m, seq=seq: m.seq == seq)
        items.append(item_from_message(msg))
        if progress is not None:
            progress(seq, n)
    link.mav.mission_ack_send(target[0], target[1], M.MAV_MISSION_ACCEPTED, MISSION)
    home = link.home_position(timeout, retries + 1)
    home_t = None
    if home is not None:
        home_t = (home.latitude / HOME_LATLON_SCALE, home.longitude / HOME_LATLON_SCALE, home.altitude / HOME_ALT_SCALE)
    return Mission(tuple(items), home_t)


def clear(link: Link, timeout: float = TIMEOUT_S, retries: int = RETRIES) -> None:
    target = (link.target_system, link.target_component)

    def send():
        link.mav.mission_clear_all_send(target[0], target[1], MISSION)

    ack = _ask(link, send, "MISSION_ACK", timeout, retries, "MISSION_CLEAR_ALL")
    if ack.type != M.MAV_MISSION_ACCEPTED:
        raise OperationError(f"mission clear rejected by the vehicle: {result_name(ack.type)}")


def _ask(link: Link, send, types, timeout: float, retries: int, what: str, condition=None):
    """Send, wait for an answer of ``types`` (an error MISSION_ACK ends it), retry on timeout."""
    types = [types] if isinstance(types, str) else list(types)
    listen = types + ([] if "MISSION_ACK" in types else ["MISSION_ACK"])
    for _ in range(retries + 1):
        send()
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            msg = link.recv(listen, left, _mission_msg) if left > 0 else None
            if msg is None:
                break
            if msg.get_type() == "MISSION_ACK" and "MISSION_ACK" not in types:
                if msg.type != M.MAV_MISSION_ACCEPTED:
                    raise OperationError(f"{what}: vehicle answered {result_name(msg.type)}")
                continue
            if condition is None or condition(msg):
                return msg
    raise OperationError(f"{what}: no answer from the vehicle ({retries} retries, {timeout:g} s each)")

