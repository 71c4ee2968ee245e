"""What a rig keeps across restarts: an open state directory with its documents.

* ``params.json`` - parameters set over MAVLink (:mod:`rig_emulator.link.parameters.store`);
* ``mission.json`` - the mission (:mod:`rig_emulator.link.mission.store`);
* ``signing.json`` - the MAVLink signing timestamp and the recent replay table
  (``{"format": "hilms-sil signing", "version": 1, "timestamp": T, "streams": [[link, sys,
  comp, T], ...]}``), only with ``--signing-key``; the key itself is never stored.

:class:`RigState` opens and locks the directory and reads every document before the rig
serves anything (a bad one is a :class:`~rig_emulator.link.state.directory.StateError` naming
it); :meth:`RigState.restore` applies the parameters and the mission to a new server.
``wipe`` removes the three documents first.
"""

from __future__ import annotations

from rig_emulator.link.mission import store as mission_store

from rig_emulator.link.parameters import store as param_store
from rig_emulator.link.mission.store import MissionStore
from rig_emulator.link.parameters.store import ParamStore
from rig_emulator.link.signing.clock import MAX_TIMESTAMP
from rig_emulator.link.state.directory import StateDir

SIGNING_FILE = "signing.json"
SIGNING_FORMAT = "hilms-sil signing"
SIGNING_VERSION = 1


def _stamp(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= MAX_TIMESTAMP


def parse_signing(doc: dict, state: StateDir) -> tuple[int, dict]:
    """(timestamp, {(link, sys, comp): timestamp}) of a signing document."""
    ts = doc.get("timestamp")
    if not _stamp(ts):
        raise state.error(SIGNING_FILE, "timestamp", f"expected a whole number in 0..2^48-1, got {ts!r}"[:120])
    streams = doc.get("streams", [])
    if not isinstance(streams, list):
        raise state.error(SIGNING_FILE, "streams", "expected a list")
    out = {}
    for k, entry in enumerate(streams):
        if (not isinstance(entry, list) or len(entry) != 4 or not all(_stamp(v) for v in entry)
                or not all(v <= 255 for v in entry[:3])):
            raise state.error(SIGNING_FILE, f"streams[{k}]", "expected [link id, system id, component id, timestamp]")
        out[tuple(entry[:3])] = entry[3]
    return ts, out


class RigState:
    def __init__(self, path, home, wipe: bool = False):
        self.dir = StateDir(path)
        self.home = home
        self.wiped: list[str] = []
        try:
            if wipe:
                self.wiped = [n for n in (param_store.FILE, mission_store.FILE, SIGNING_FILE) if self.dir.remove(n)]
            self.params = ParamStore(self.dir)
            self.mission = MissionStore(self.dir, home)
            doc = self.dir.read_json(SIGNING_FILE, SIGNING_FORMAT, SIGNING_VERSION)
            self.signing_stored = None if doc is None else parse_signing(doc, self.dir)
        except BaseException:
            self.dir.close()
            raise

    @property
    def path(self):
        return self.dir.path

    def restore(self, server) -> str:
        """Apply the stored parameters, then the stored mission, to ``server``; a line saying what."""
        names = self.params.apply(server.rig)
        what = []
        if names:
            shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
            what.append(f"{len(names)} parameter{'s' if len(names) != 1 else ''} ({shown})")
        if self.mission.items:
            try:
                server.mission.replace(self.mission.items, persist=False)
            except ValueError as exc:
                raise self.dir.error(mission_store.FILE, "items", str(exc)) from None
            what.append(f"a {len(self.mission.items)}-item mission")
        if self.wiped:
            return f"state in {self.path}: wiped ({', '.join(self.wiped)})"
        if not what:
            return f"state in {self.path}: nothing stored yet"
        return f"state in {self.path}: restored {' and '.join(what)} (--wipe starts afresh)"

    def save_signing(self, snapshot: tuple) -> None:
        timestamp, streams = snapshot
        doc = {"format": SIGNING_FORMAT, "version": SIGNING_VERSION, "timestamp": int(timestamp),
               "streams": sorted([*key, int(ts)] for key, ts in streams.items())}
        self.dir.write_json(SIGNING_FILE, doc)

    def close(self) -> None:
        self.dir.close()
