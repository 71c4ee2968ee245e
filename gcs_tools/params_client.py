"""The MAVLink parameter protocol, ground side: list, read, set with verification, load with rollback.

Follows https://mavlink.io/en/services/parameter.html as QGroundControl does it, with its
retry counts (4 retries of PARAM_REQUEST_LIST, 5 of each index re-request, read and write):

* **list**: PARAM_REQUEST_LIST, then every PARAM_VALUE is kept by ``param_index``. When
  nothing new has come for ``timeout`` seconds, the indices still missing are requested one
  by one with PARAM_REQUEST_READ (by index), all of them in flight at once, again after each
  silent ``timeout``; an index still missing after ``index_retries`` requests ends the list
  with an error naming it. Duplicates and re-ordered messages are harmless (kept by index);
  a change of ``param_count`` or two indices with one name is an error, never a silent mix.
* **read**: PARAM_REQUEST_READ by name, ``retries`` resends.
* **set**: PARAM_SET, and the vehicle's PARAM_VALUE echo must carry the value set (float32
  equal). An echo with another value is the vehicle keeping its value (rejected) or a stale
  message: the set is sent again; only if every attempt was answered with another value is
  it reported rejected (with the vehicle's STATUSTEXT reason, if it sent one). No echo in
  ``retries + 1`` attempts is a timeout. PARAM_SET is idempotent, so resends are safe.
* **load** (:func:`load`): the whole file is checked first (names exist on the vehicle,
  values fit their types); then each value that differs is set and verified; if one fails,
  those already changed are set back to the values read before, so a failed load leaves the
  vehicle as it was (or says which parameters it could not restore). The rig's read-only
  parameters (:data:`READ_ONLY`: values it derives, such as MPC_THR_HOVER, which a saved file
  holds as they were then) are left as the vehicle has them.

Values are sent in the vehicle's type as floats (the cast encoding; the rig uses REAL32 for
every parameter). Failures raise :class:`~gcs_tools.errors.OperationError`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from gcs_tools.errors import OperationError, UsageError
from gcs_tools.param_files import ParamLine, check_value
from protocol.dialect import mavlink as M

TIMEOUT_S = 1.0
LIST_RETRIES = 4  # QGroundControl: _maxInitialRequestListRetry
RETRIES = 5  # QGroundControl: _maxReadWriteRetry, _maxInitialLoadRetrySingleParam
INDEX_WINDOW = 32  # index re-requests in flight at once


@dataclass(frozen=True)
class Param:
    name: str
    value: float
    ptype: int
    index: int
    count: int


def _param(msg) -> Param:
    return Param(msg.param_id, float(msg.param_value), int(msg.param_type), int(msg.param_index), int(msg.param_count))


def same_value(a: float, b: float, ptype: int = M.MAV_PARAM_TYPE_REAL32) -> bool:
    """Equal as the wire carries them (float32 unless REAL64)."""
    if ptype == M.MAV_PARAM_TYPE_REAL64:
        return a == b
    return bool(np.float32(a) == np.float32(b))


class ParamClient:
    def __init__(self, link, timeout: float = TIMEOUT_S, retries: int = RETRIES, list_retries: int = LIST_RETRIES):
        self.link = link
        self.timeout = timeout
        self.retries = retries
        self.list_retries = list_retries
        self.resends = 0  # requests sent again (figures for the lossy-link tests)

    @property
    def _target(self):
        return self.link.target_system, self.link.target_component

    def _recv(self, timeout: float, condition=None):
        comp = self.link.target_component

        def mine(m):
            return m.get_srcComponent() == comp and (condition is None or condition(m))

        return self.link.recv("PARAM_VALUE", timeout, mine)

    # --- list ------------------------------------------------------------------------------------
    def fetch_all(self, progress=None) -> dict[str, Param]:
        """Every parameter of the vehicle, by name."""
        ts, tc = self._target
        got: dict[int, Param] = {}
        count = None
        self.link.mav.param_request_list_send(ts, tc)
        list_tries = 0
        asked: dict[int, int] = {}  # index -> re-requests sent
        while count is None or len(got) < count:
            msg = self._recv(self.timeout)
            if msg is not None:
                p = _param(msg)
                if p.index == 65535 or p.count == 0:
                    continue  # an echo of a set, not part of the list
                if count is not None and p.count != count:
                    raise OperationError(f"parameter list: the vehicle's parameter count changed from {count} to "
                                         f"{p.count} during the download")
                count = p.count
                if p.index >= count:
                    raise OperationError(f"parameter list: index {p.index} of a {count}-parameter list")
                if p.index not in got:
                    got[p.index] = p
                    if progress is not None:
                        progress(len(got), count)
                continue
            if count is None:  # silence: nothing at all yet
                list_tries += 1
                if list_tries > self.list_retries:
                    raise OperationError(f"parameter list: no PARAM_VALUE after {self.list_retries + 1} "
                                         f"PARAM_REQUEST_LIST ({self.timeout:g} s each)")
                self.resends += 1
                self.link.mav.param_request_list_send(ts, tc)
                continue
            missing = [i for i in range(count) if i not in got]
            failed = [i for i in missing if asked.get(i, 0) >= self.retries]
            if failed:
                raise OperationError(f"parameter list: {len(failed)} of {count} parameters missing after "
                                     f"{self.retries} requests each (indices {', '.join(map(str, failed[:10]))}"
                                     f"{', ...' if len(failed) > 10 else ''})")
            for i in missing[:INDEX_WINDOW]:
                asked[i] = asked.get(i, 0) + 1
                self.resends += 1
                self.link.mav.param_request_read_send(ts, tc, b"", i)
        by_name: dict[str, Param] = {}
        for p in got.values():
            if p.name in by_name:
                raise OperationError(f"parameter list: indices {by_name[p.name].index} and {p.index} are both "
                                     f"named {p.name}")
            by_name[p.name] = p
        return by_name

    # --- read / set ------------------------------------------------------------------------------------
    def read(self, name: str) -> Param:
        ts, tc = self._target
        for attempt in range(self.retries + 1):
            self.resends += attempt > 0
            self.link.mav.param_request_read_send(ts, tc, name.encode("ascii"), -1)
            msg = self._recv(self.timeout, lambda m: m.param_id == name)
            if msg is not None:
                return _param(msg)
        raise OperationError(f"{name}: no PARAM_VALUE after {self.retries + 1} PARAM_REQUEST_READ "
                             f"({self.timeout:g} s each): no such parameter, or no link")

    def set(self, name: str, value: float, ptype: int = M.MAV_PARAM_TYPE_REAL32) -> Param:
        """Set and verify by the echo; returns the echoed parameter."""
        why = check_value(value, ptype, f"{name} value")
        if why:
            raise UsageError(why)
        ts, tc = self._target
        kept = None
        reasons: dict = {}  # STATUSTEXT id (or text) -> text about this parameter
        for attempt in range(self.retries + 1):
            self.resends += attempt > 0
            self.link.mav.param_set_send(ts, tc, name.encode("ascii"), float(value), ptype)
            deadline = time.monotonic() + self.timeout
            while time.monotonic() < deadline:
                msg = self.link.recv(["PARAM_VALUE", "STATUSTEXT"], deadline - time.monotonic())
                if msg is None:
                    break
                if msg.get_type() == "STATUSTEXT":
                    _note_reason(msg, name, reasons)
                    continue
                if msg.param_id != name:
                    continue
                if same_value(msg.param_value, value, ptype):
                    return _param(msg)
                kept = float(msg.param_value)
                break  # the vehicle kept another value (or a stale echo): send again
        if kept is None:
            raise OperationError(f"{name}: no PARAM_VALUE echo after {self.retries + 1} PARAM_SET "
                                 f"({self.timeout:g} s each)")
        texts = dict.fromkeys(t.strip() for t in reasons.values())  # one line per distinct reason: every resend
        why = f" ({'; '.join(texts)})" if texts else ""                 # of the set is refused with the same text
        raise OperationError(f"{name}: the vehicle rejected {value:g} and kept {kept:g}{why}")


def _note_reason(msg, name: str, reasons: dict) -> None:
    """Collect STATUSTEXTs about ``name``, joining the chunks of a long one (same ``id``)."""
    text = msg.text if isinstance(msg.text, str) else msg.text.decode("ascii", "replace")
    key = msg.id if getattr(msg, "id", 0) else text
    if key in reasons and msg.id:
        if msg.chunk_seq > 0:
            reasons[key] += text
        return
    if name in text and key not in reasons:
        reasons[key] = text


def _read_only_names() -> frozenset:
    from rig_emulator.link.parameters.table import DERIVED

    return frozenset(DERIVED)


READ_ONLY = _read_only_names()


def load(client: ParamClient, lines: list[ParamLine], source: str, report=None) -> tuple[int, int]:
    """Set every parameter of a parsed file; returns (set, already equal or read-only). See the
    module doc."""
    current = client.fetch_all()
    for ln in lines:  # the whole file against the vehicle before anything is sent
        if ln.name not in current:
            raise UsageError(f"{source}:{ln.line}: {ln.name}: no such parameter on the vehicle; nothing was set")
        why = check_value(ln.value, current[ln.name].ptype, f"{ln.name} value")
        if why:
            raise UsageError(f"{source}:{ln.line}: {why}; nothing was set")
    changed: list[Param] = []
    unchanged = 0
    for ln in lines:
        old = current[ln.name]
        if same_value(old.value, ln.value, old.ptype) or ln.name in READ_ONLY:
            unchanged += 1
            continue
        try:
            client.set(ln.name, ln.value, old.ptype)
        except OperationError as exc:
            raise OperationError(f"{source}:{ln.line}: {exc}; " + _restore(client, changed)) from None
        changed.append(old)
        if report is not None:
            report(ln.name, old.value, ln.value)
    return len(changed), unchanged


def _restore(client: ParamClient, changed: list[Param]) -> str:
    if not changed:
        return "nothing had been changed"
    failed = []
    for p in reversed(changed):
        try:
            client.set(p.name, p.value, p.ptype)
        except OperationError:
            failed.append(p.name)
    if failed:
        return (f"{len(changed) - len(failed)} parameters set before were restored, but NOT "
                f"{', '.join(failed)} (set them back by hand)")
    return f"the {len(changed)} parameters set before were restored"
