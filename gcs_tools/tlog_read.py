"""Reading .tlog files (any MAVLink vehicle's) into per-message arrays.

A .tlog is a sequence of records: an 8-byte big-endian time stamp (microseconds since 1970)
followed by one MAVLink 1 or 2 frame. Files are decoded with the hilms dialect's generated
pymavlink module (a superset of common.xml, so other vehicles' logs decode too; messages of
other dialects are skipped). The frames are walked as pymavlink's indexed log reader
(``mavutil.mavmmaplog``) walks them, from each frame's length byte, and only the frames of the
message types asked for are decoded (``MAVLink.decode``, which checks their CRC): reading four
types of a 60 s log takes a fraction of pymavlink's message-by-message parse. Where no frame
starts (no marker byte, a truncated frame, a decoded frame whose CRC fails) the walk moves on
by one byte, as pymavlink's robust parsing does. The file is mapped, not read into memory;
only the fields asked for are kept, as float64 arrays.
"""

from __future__ import annotations

import math
import mmap
import os
import struct
from collections import defaultdict

import numpy as np

from gcs_tools.errors import UsageError
from protocol.dialect import mavlink as M

#: message type -> the fields :func:`read_fields` keeps by default for the ground tools
TIME_FIELDS = ("time_boot_ms", "time_usec")

_STAMP = struct.Struct(">Q")
_V1, _V2 = 0xFE, 0xFD


def _open_map(path):
    if not os.path.isfile(path):
        raise UsageError(f"{path}: no such file")
    try:
        with open(path, "rb") as f:
            if os.fstat(f.fileno()).st_size == 0:
                return b""
            return mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
    except OSError as exc:
        raise UsageError(f"{path}: cannot read: {exc.strerror}") from None


def _records(data, wanted: set | None):
    """``(frames so far, message or None)`` for every frame of the log, in file order (see the
    module doc); the message is decoded only when its id is in ``wanted`` (every known id when
    None)."""
    n = len(data)
    known = M.mavlink_map
    mav = M.MAVLink(None)
    stamp = _STAMP.unpack_from
    signed_flag, signature = M.MAVLINK_IFLAG_SIGNED, M.MAVLINK_SIGNATURE_BLOCK_LEN
    count = 0
    ofs = 0
    while ofs + 16 <= n:
        marker = data[ofs + 8]
        if marker == _V2:
            if ofs + 20 > n:
                return
            mid = data[ofs + 15] | (data[ofs + 16] << 8) | (data[ofs + 17] << 16)
            body = 10 + data[ofs + 9]
            flen = body + 2 + (signature if data[ofs + 10] & signed_flag else 0)
        elif marker == _V1:
            mid = data[ofs + 13]
            body = 6 + data[ofs + 9]
            flen = body + 2
        else:
            ofs += 1
            continue
        end = ofs + 8 + flen
        if end > n:
            ofs += 1  # a truncated last frame, or no frame at all: look further
            continue
        cls = known.get(mid)
        if cls is None:
            ofs = end
            continue
        if wanted is None or mid in wanted:
            try:
                msg = mav.decode(bytearray(data[ofs + 8:end]))
            except M.MAVError:
                ofs += 1
                continue
            msg._timestamp = stamp(data, ofs)[0] * 1.0e-6  # as pymavlink's log readers stamp it
            count += 1
            yield count, msg
        else:  # not decoded: trusted by its length, as pymavlink's indexed reader does; a damaged
            count += 1  # length lands on a byte that is no marker (skipped) or a frame whose CRC fails
            yield count, None
        ofs = end


def _type_ids(types) -> set | None:
    if types is None:
        return None
    return {mid for mid, cls in M.mavlink_map.items() if cls.msgname in types}


def _iter_counted(path, types=None):
    """``(frames so far, message or None)`` for every good frame of the log at ``path``; the
    message is decoded only when its type is in ``types`` (every type when None)."""
    data = _open_map(path)
    try:
        yield from _records(data, _type_ids(types))
    finally:
        if isinstance(data, mmap.mmap):
            data.close()


def iter_tlog(path, types=None):
    """Every decoded message of the log (of ``types`` if given), in file order."""
    for _, msg in _iter_counted(path, types):
        if msg is not None:
            yield msg


def read_fields(path, spec: dict, sysid: int | None = None) -> tuple[dict, dict]:
    """Arrays of the fields in ``spec`` ({message type: [field, ...]}), one row per message.

    Returns ``(arrays, info)``: ``arrays[type][field]`` float64 arrays (plus ``"_t"``, the
    record timestamp in s), ``info`` with ``counts`` per type, ``messages`` in all and the
    ``sysid`` whose messages were kept (``sysid`` or the first vehicle that sent one of the
    types; other systems are ignored). NAMED_VALUE_FLOAT fields are given by name
    (``NAMED_VALUE_FLOAT: ["LC1_N", ...]``) and become ``{name: values, name + "_ms": times}``.
    """
    rows: dict = {k: defaultdict(list) for k in spec}
    counts: dict = defaultdict(int)
    total = 0
    chosen = sysid
    named = set(spec.get("NAMED_VALUE_FLOAT", ()))
    fields = {}  # kind -> (its column, field name, array index or None) per field (``name[i]``: an element)
    for kind, names in spec.items():
        if kind == "NAMED_VALUE_FLOAT":  # by value name, below
            continue
        parsed = []
        for f in names:
            base, _, rest = f.partition("[")
            parsed.append((rows[kind][f], base, int(rest[:-1]) if rest else None))
        fields[kind] = parsed
    for total, msg in _iter_counted(path, set(spec)):
        if msg is None:
            continue
        kind = msg.get_type()
        src = msg.get_srcSystem()
        if chosen is None:
            chosen = src
        if src != chosen:
            continue
        counts[kind] += 1
        out = rows[kind]
        if kind == "NAMED_VALUE_FLOAT":
            name = msg.name if isinstance(msg.name, str) else msg.name.decode("ascii", "replace")
            name = name.rstrip("\x00")
            if name in named:
                out[name].append(float(msg.value))
                out[name + "_ms"].append(float(msg.time_boot_ms))
            continue
        out["_t"].append(msg._timestamp)
        values = msg.__dict__
        for column, base, idx in fields[kind]:
            try:
                v = values[base] if idx is None else values[base][idx]
                column.append(float(v))
            except (KeyError, IndexError, TypeError, ValueError):  # a field this message lacks
                column.append(math.nan)
    if total == 0:
        raise UsageError(f"{path}: no MAVLink messages found (not a .tlog?)")
    arrays = {k: {f: np.asarray(v, dtype=float) for f, v in cols.items()} if counts.get(k) else {}
              for k, cols in rows.items()}  # a type the log lacks: no columns at all
    return arrays, {"counts": dict(counts), "messages": total, "sysid": chosen}
