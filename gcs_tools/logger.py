"""Telemetry logging to .tlog, and CSV export of chosen fields.

:func:`record` writes every message the link receives (any system, any type) with a
wall-clock timestamp, one ``write`` per record (:class:`rig_emulator.link.telemetry.tlog_export.TlogWriter`):
a logger killed at any moment leaves a valid log up to its last complete message. Nothing
is kept in memory per message, so long runs log at a steady memory.

:func:`export_csv` streams a .tlog into a CSV of chosen ``MESSAGE.field`` columns (array
elements as ``MESSAGE.field[i]``, NAMED_VALUE_FLOAT values as ``NAMED_VALUE_FLOAT.NAME``):
one row per message that carries a chosen field, the other columns holding their latest
value (empty before the first). The header names end with their unit from the dialect
(``timestamp_s``, ``ATTITUDE.roll_rad``, ``LOCAL_POSITION_NED.x_m``; ``protocol/column_units.py``).
Written to a temporary file and moved into place.
"""

from __future__ import annotations

import csv
import threading
import time
from pathlib import Path

from gcs_tools.errors import OperationError, UsageError
from gcs_tools.link import Link, message_id
from gcs_tools.tlog_read import iter_tlog
from protocol.atomic_file import atomic_path
from protocol.column_units import with_unit
from protocol.dialect import mavlink as M
from rig_emulator.link.telemetry.tlog_export import TlogWriter


def parse_fields(specs) -> list[tuple[str, str, int | None]]:
    """``["ATTITUDE.roll", "HILMS_LOAD_CELLS.thrust_n[2]", ...]`` -> (message, field, index) (UsageError if unknown)."""
    out = []
    for spec in specs:
        spec = spec.strip()
        if not spec:
            continue
        if "." not in spec:
            raise UsageError(f"--fields {spec!r}: expected MESSAGE.field")
        name, fld = spec.split(".", 1)
        name = name.upper()
        cls = M.mavlink_map.get(message_id(name))
        if name == "NAMED_VALUE_FLOAT" and fld not in cls.fieldnames:
            out.append((name, fld, None))  # a NAMED_VALUE_FLOAT by its name
            continue
        index = None
        if fld.endswith("]") and "[" in fld:
            fld, idx = fld[:-1].split("[", 1)
            if not idx.isdigit():
                raise UsageError(f"--fields {spec!r}: bad index {idx!r}")
            index = int(idx)
        if fld not in cls.fieldnames:
            raise UsageError(f"--fields {spec!r}: {name} has no field {fld!r} (fields: {', '.join(cls.fieldnames)})")
        length = cls.array_lengths[cls.ordered_fieldnames.index(fld)]
        if index is not None and not (length and index < length):
            raise UsageError(f"--fields {spec!r}: {name}.{fld} is not an array of more than {index} elements")
        out.append((name, fld, index))
    if not out:
        raise UsageError("--fields: no field given")
    return out


def _header(message: str, field: str, index) -> str:
    """``MESSAGE.field[i]`` followed by its unit from the dialect (``ATTITUDE.roll_rad``); a
    NAMED_VALUE_FLOAT value keeps its name (the rig's names end with their unit: ``LC1_N``)."""
    name = f"{message}.{field}" + ("" if index is None else f"[{index}]")
    cls = next((c for c in M.mavlink_map.values() if c.msgname == message), None)
    return with_unit(name, getattr(cls, "fieldunits_by_name", {}).get(field))


def export_csv(tlog, csv_path, fields: list[str]) -> int:
    """Write the chosen fields of ``tlog`` as CSV (atomically); returns the number of rows."""
    parsed = parse_fields(fields)
    headers = [_header(m, f, i) for m, f, i in parsed]
    latest = [""] * len(parsed)
    by_type: dict = {}
    for col, (m, f, i) in enumerate(parsed):
        by_type.setdefault(m, []).append((col, f, i))
    rows = 0
    with atomic_path(csv_path) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["timestamp_s", *headers])
            for msg in iter_tlog(tlog, set(by_type)):
                hit = False
                for col, f, i in by_type[msg.get_type()]:
                    if msg.get_type() == "NAMED_VALUE_FLOAT" and i is None and f not in msg.fieldnames:
                        name = msg.name if isinstance(msg.name, str) else msg.name.decode("ascii", "replace")
                        if name.rstrip("\x00") != f:
                            continue
                        latest[col] = repr(float(msg.value))
                    else:
                        v = getattr(msg, f)
                        v = v[i] if i is not None else v
                        latest[col] = v.decode("ascii", "replace") if isinstance(v, bytes) else repr(v)
                    hit = True
                if hit:
                    w.writerow([f"{msg._timestamp:.6f}", *latest])
                    rows += 1
    return rows


class Recorder:
    """Log a link to a .tlog until :meth:`stop` (or ``duration`` s); usable in a thread."""

    def __init__(self, link: Link, path, duration: float | None = None, link_timeout_s: float = 5.0):
        self.link = link
        self.path = Path(path)
        self.duration = duration
        self.link_timeout_s = link_timeout_s
        self.writer = TlogWriter(self.path)
        self.count = 0
        self.error: BaseException | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def stop(self) -> None:
        self._stop.set()

    def run(self) -> int:
        """Record until stopped or ``duration`` s; OperationError when the link goes silent."""
        conn = self.link.conn
        t_end = None if self.duration is None else time.monotonic() + self.duration
        last = time.monotonic()
        try:
            while not self._stop.is_set():
                now = time.monotonic()
                if t_end is not None and now >= t_end:
                    break
                wait = 0.2 if t_end is None else max(min(0.2, t_end - now), 0.0)
                self.link.heartbeat_if_due()  # a ground station's HEARTBEAT at 1 Hz (gcs_tools.link)
                try:
                    msg = conn.recv_match(blocking=True, timeout=wait)
                except OSError as exc:
                    raise OperationError(f"link {self.link.url} lost: {exc}") from None
                if msg is None:
                    if time.monotonic() - last > self.link_timeout_s:
                        raise OperationError(f"link lost: nothing received for {self.link_timeout_s:g} s")
                    continue
                if msg.get_type() == "BAD_DATA":
                    continue
                last = time.monotonic()
                self.writer.write_raw(msg.get_msgbuf(), time.time())
                self.count += 1
        finally:
            self.writer.close()
        return self.count

    def start(self) -> "Recorder":
        def target():
            try:
                self.run()
            except BaseException as exc:  # noqa: BLE001 - handed to the caller by join()
                self.error = exc

        self._thread = threading.Thread(target=target, daemon=True)
        self._thread.start()
        return self

    def join(self, timeout: float = 10.0) -> int:
        self.stop()
        if self._thread is not None:
            self._thread.join(timeout)
        if self.error is not None:
            raise self.error
        return self.count


def request_rates(link: Link, rates: dict[str, float], stream_hz: float | None) -> None:
    """Ask for ``rates`` ({message name: Hz}) with SET_MESSAGE_INTERVAL, all streams with REQUEST_DATA_STREAM."""
    if stream_hz is not None:
        link.request_data_streams(stream_hz)
    for name, hz in rates.items():
        link.set_message_rate(message_id(name), hz)
