"""The recorded time series written to a file chunk by chunk (``rig-emulator simulate --out``).

Each writer takes log rows (:mod:`rig_emulator.simulation.log_layout`) as they are simulated
(:meth:`write`), so a run of any length needs memory for one chunk only, and produces the
file a whole-series export would: ``.npz`` holds one array per series name (``t``, ``pos``
(n, 3), ...; what ``numpy.savez_compressed`` of :attr:`SimResult.series` writes), ``.csv``
one column per component with a header line of names that end with their unit
(``t_s``, ``pos_0_m``, ``euler_0_rad``, ``u_1_Nm``; :data:`UNITS`, ``protocol/column_units.py``). :meth:`commit` finishes the file and moves
it into place atomically (``protocol/atomic_file.py``); :meth:`abort` removes everything
written and leaves an existing file as it was.

``.npz`` members must each be written whole, so the columns go to one raw scratch file per
series in a scratch directory next to the output (about 0.5 kB per log row, removed at the
end) and are compressed into the archive at :meth:`commit`.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import zipfile
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from protocol.atomic_file import atomic_path
from protocol.column_units import with_unit
from rig_emulator.simulation import log_layout as L

COPY_BYTES = 16 * 1024 * 1024

#: unit of each series of the log (SI, as the step loop records it; log_layout.py), per component
#: where they differ; "" for codes, flags and the dimensionless virtual inputs of Eq. 34
UNITS = {
    "t": "s", "pos": "m", "vel": "m/s", "euler": "rad", "omega": "rad/s", "pos_des": "m", "vel_des": "m/s",
    "euler_des": "rad", "thrust": "N", "v_cmd": "V", "u": ("N", "N m", "N m", "N m"), "s": "rad/s", "flags": "",
    "waypoint": "", "euler_rate": "rad/s", "euler_rate_des": "rad/s", "mode": "", "uxy": "", "pos_true": "m",
    "euler_true": "rad", "thrust_meas": "N", "health": "", "failsafe": "", "estimate_invalid": "",
}


def csv_columns() -> tuple[list[int], list[str]]:
    """Log column and header name of every CSV column (``t_s``; ``pos_0_m``, ``pos_1_m``, ... for vectors)."""
    cols, names = [], []
    for name, (start, width) in L.NAMES.items():
        units = UNITS[name] if isinstance(UNITS[name], tuple) else (UNITS[name],) * width
        if width == 1:
            cols.append(start)
            names.append(with_unit(name, units[0]))
        else:
            for i in range(width):
                cols.append(start + i)
                names.append(with_unit(f"{name}_{i}", units[i]))
    return cols, names


def bytes_per_row(suffix: str) -> int:
    """Disk bytes a log row needs while it is written (scratch files for .npz), roughly."""
    return 8 * L.NCOLS if suffix == ".npz" else 16 * L.NCOLS


class _Writer:
    def __init__(self, path):
        self.path = Path(path)
        self.rows = 0
        self._stack = ExitStack()
        self.tmp = self._stack.enter_context(atomic_path(self.path))

    def commit(self) -> None:
        self._finish()
        self._stack.close()

    def abort(self) -> None:
        try:
            self._discard()
        finally:
            self._stack.__exit__(RuntimeError, RuntimeError("aborted"), None)

    def _finish(self) -> None:
        raise NotImplementedError

    def _discard(self) -> None:
        pass


class CsvSeriesWriter(_Writer):
    """One line per log row, ``%.9g``, comma-separated, a header line of column names."""

    def __init__(self, path):
        super().__init__(path)
        self._cols, names = csv_columns()
        self._fh = open(self.tmp, "w", newline="\n")
        self._fh.write(",".join(names) + "\n")

    def write(self, rows: np.ndarray) -> None:
        if rows.shape[0]:
            np.savetxt(self._fh, rows[:, self._cols], delimiter=",", fmt="%.9g")
        self.rows += rows.shape[0]

    def _finish(self) -> None:
        self._fh.close()

    def _discard(self) -> None:
        self._fh.close()


class NpzSeriesWriter(_Writer):
    """One ``.npy`` member per series name, deflate-compressed, as ``numpy.savez_compressed``."""

    def __init__(self, path):
        super().__init__(path)
        self._scratch = tempfile.mkdtemp(prefix=f".{self.path.name}.", suffix=".parts", dir=self.path.parent)
        self._files = {name: open(os.path.join(self._scratch, name), "wb") for name in L.NAMES}

    def write(self, rows: np.ndarray) -> None:
        for name, (start, width) in L.NAMES.items():
            part = rows[:, start] if width == 1 else rows[:, start : start + width]
            self._files[name].write(np.ascontiguousarray(part, dtype="<f8").tobytes())
        self.rows += rows.shape[0]

    def _finish(self) -> None:
        try:
            for fh in self._files.values():
                fh.close()
            with zipfile.ZipFile(self.tmp, mode="w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
                for name, (_, width) in L.NAMES.items():
                    shape = (self.rows,) if width == 1 else (self.rows, width)
                    header = {"descr": np.lib.format.dtype_to_descr(np.dtype("<f8")), "fortran_order": False,
                              "shape": shape}
                    with zf.open(name + ".npy", "w", force_zip64=True) as member, \
                            open(os.path.join(self._scratch, name), "rb") as src:
                        np.lib.format.write_array_header_1_0(member, header)
                        shutil.copyfileobj(src, member, COPY_BYTES)
        finally:
            shutil.rmtree(self._scratch, ignore_errors=True)

    def _discard(self) -> None:
        for fh in self._files.values():
            fh.close()
        shutil.rmtree(self._scratch, ignore_errors=True)


WRITERS = {".npz": NpzSeriesWriter, ".csv": CsvSeriesWriter}
