"""Calibration results on disk: JSON next to a run's config, written atomically.

``save_calibration(path, cal)`` writes an :class:`ImuCalibration` or a
:class:`LoadCellCalibration` to a temporary file in the target directory and moves it
into place with ``os.replace`` (a crash never leaves a half-written file).
``load_calibration(path)`` reads it back and raises ``ValueError`` naming the file when
it is not a valid calibration.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from protocol.atomic_file import atomic_path

from rig_emulator.build_cache import BuildCache
from rig_emulator.estimation.imu_calibration import ImuCalibration
from rig_emulator.estimation.load_cell_calibration import LoadCellCalibration

FORMAT_VERSION = 1


def _plain(value):
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def save_calibration(path: str | os.PathLike, cal: ImuCalibration | LoadCellCalibration) -> Path:
    """Write ``cal`` as JSON to ``path`` atomically; returns the path."""
    path = Path(path)
    if isinstance(cal, ImuCalibration):
        doc = {"kind": "imu", "gain": cal.gain.tolist(), "offset_counts": cal.offset_counts.tolist(),
               "residual_rms": np.nan_to_num(cal.residual_rms, nan=-1.0).tolist()}
    elif isinstance(cal, LoadCellCalibration):
        doc = {"kind": "load_cell", "zero_counts": cal.zero_counts.tolist(),
               "c_grf_per_count": cal.c_grf_per_count.tolist()}
    else:
        raise TypeError(f"save_calibration: cannot save a {type(cal).__name__}")
    doc["format_version"] = FORMAT_VERSION
    doc["procedure"] = _plain(cal.procedure)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=1)
    return path


def _array(doc: dict, key: str, shape_len: int, path: Path) -> np.ndarray:
    try:
        arr = np.asarray(doc[key], dtype=np.float64)
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: calibration file is corrupt: field {key!r} missing or not numeric") from exc
    if arr.ndim != shape_len or not np.all(np.isfinite(arr)):
        raise ValueError(f"{path}: calibration file is corrupt: field {key!r} must be a finite {shape_len}-d array")
    return arr


_READ = BuildCache(32)  # (path, inode, size, mtime) -> calibration read from it


def load_calibration(path: str | os.PathLike) -> ImuCalibration | LoadCellCalibration:
    """Read a calibration written by :func:`save_calibration`.

    A file read before and unchanged since (same inode, size and modification time: a new
    calibration is written by rename, so it has a new inode) is not parsed again: a sweep's
    runs share one calibration file. Every call returns its own copy.
    """
    path = Path(path)
    try:
        st = path.stat()
    except OSError:
        return _read_calibration(path)  # reports the error
    key = (str(path.resolve()), st.st_ino, st.st_size, st.st_mtime_ns)
    return _READ.get_or_build(key, lambda: _read_calibration(path))


def _read_calibration(path: Path) -> ImuCalibration | LoadCellCalibration:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError as exc:
        raise ValueError(f"{path}: calibration file not found") from exc
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: calibration file is corrupt (not valid JSON: {exc})") from exc
    if not isinstance(doc, dict) or doc.get("format_version") != FORMAT_VERSION:
        raise ValueError(f"{path}: calibration file is corrupt or of an unknown format (format_version != {FORMAT_VERSION})")
    procedure = doc.get("procedure", {})
    if doc.get("kind") == "imu":
        gain = _array(doc, "gain", 4, path)
        offset = _array(doc, "offset_counts", 3, path)
        resid = _array(doc, "residual_rms", 2, path)
        n = gain.shape[0]
        if gain.shape != (n, 3, 3, 3) or offset.shape != (n, 3, 3) or resid.shape != (n, 3):
            raise ValueError(f"{path}: calibration file is corrupt: IMU arrays have inconsistent shapes "
                             f"{gain.shape}, {offset.shape}, {resid.shape}")
        resid[resid < 0] = np.nan
        return ImuCalibration(gain, offset, resid, procedure)
    if doc.get("kind") == "load_cell":
        zero = _array(doc, "zero_counts", 1, path)
        c = _array(doc, "c_grf_per_count", 1, path)
        if zero.shape != c.shape:
            raise ValueError(f"{path}: calibration file is corrupt: zero_counts and c_grf_per_count differ in length")
        return LoadCellCalibration(zero, c, procedure)
    raise ValueError(f"{path}: calibration file is corrupt: kind must be 'imu' or 'load_cell'")
