"""Reading .tlog files (any MAVLink vehicle's) into per-message arrays.

Files are read with pymavlink's ``mavutil.mavlogfile`` in the hilms dialect (a superset of
common.xml, so other vehicles' logs decode too; messages of other dialects come back as
``UNKNOWN_<id>`` and are skipped). Reading streams the file: only the fields asked for are
kept, as float64 arrays.
"""

from __future__ import annotations

import math
import os
from collections import defaultdict

import numpy as np

from gcs_tools.errors import UsageError
from protocol.dialect import use_hilms_dialect

#: message type -> the fields :func:`read_fields` keeps by default for the ground tools
TIME_FIELDS = ("time_boot_ms", "time_usec")


def open_tlog(path):
    """A pymavlink log reader of ``path`` (UsageError when it cannot be opened)."""
    use_hilms_dialect()
    from pymavlink import mavutil

    if not os.path.isfile(path):
        raise UsageError(f"{path}: no such file")
    try:
        return mavutil.mavlogfile(str(path), robust_parsing=True)
    except OSError as exc:
        raise UsageError(f"{path}: cannot read: {exc.strerror}") from None


def iter_tlog(path, types=None):
    """Every decoded message of the log (of ``types`` if given), in file order."""
    log = open_tlog(path)
    try:
        while True:
            msg = log.recv_msg()
            if msg is None:
                return
            kind = msg.get_type()
            if kind == "BAD_DATA" or kind.startswith("UNKNOWN"):
                continue
            if types is None or kind in types:
                yield msg
    finally:
        log.close()


def _value(msg, name: str):
    """Field ``name`` of ``msg``; ``name[i]`` indexes an array field."""
    if name.endswith("]"):
        base, idx = name[:-1].split("[")
        return getattr(msg, base)[int(idx)]
    return getattr(msg, name)


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
    for msg in iter_tlog(path):
        total += 1
        kind = msg.get_type()
        if kind not in spec:
            continue
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
        out["_t"].append(float(getattr(msg, "_timestamp", math.nan)))
        for f in spec[kind]:
            try:
                out[f].append(float(_value(msg, f)))
            except (AttributeError, IndexError, TypeError, ValueError):
                out[f].append(math.nan)
    if total == 0:
        raise UsageError(f"{path}: no MAVLink messages found (not a .tlog?)")
    arrays = {k: {f: np.asarray(v, dtype=float) for f, v in cols.items()} for k, cols in rows.items()}
    return arrays, {"counts": dict(counts), "messages": total, "sysid": chosen}
