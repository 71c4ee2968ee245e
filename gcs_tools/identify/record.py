"""The record of an identification: one JSON line per evaluated parameter point.

Each line holds the fit's *context* fingerprint (what is simulated and compared: targets,
scenarios, seed, airframe, configuration files, the emulator's own source files), the point
(``{key: value}``), what the simulation gave (``metrics``: named numbers) and the residual
vector (float64, zlib-compressed, base64: bit-exact). Runs are bit-identical for the same
seed and configuration, so a point found in the record with the same context is not
simulated again: rerunning the same command replays the optimiser's path from the record
and continues where it stopped (a ``--max-evals`` budget, Ctrl-C, a crash).

Lines are appended with one ``write`` each and flushed, so an interrupted fit leaves at most
a truncated last line, which is skipped on reading. Lines of another context (another
emulator build, other targets) are kept in the file and ignored.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import os
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs_tools.errors import UsageError


def canonical(obj) -> str:
    """Deterministic JSON text of ``obj`` (sorted keys, floats as repr)."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True)


def digest(obj) -> str:
    return hashlib.sha256(canonical(obj).encode()).hexdigest()


def point_key(context: str, point: dict) -> str:
    return digest({"context": context, "point": point})


def pack(a: np.ndarray) -> str:
    return base64.b64encode(zlib.compress(np.ascontiguousarray(a, dtype="<f8").tobytes(), 6)).decode("ascii")


def unpack(text: str) -> np.ndarray:
    return np.frombuffer(zlib.decompress(base64.b64decode(text)), dtype="<f8").copy()


def _json_safe(metrics: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in metrics.items()}


@dataclass
class Evaluation:
    """What one parameter point gave."""

    point: dict  # {key: value}
    residuals: np.ndarray  # the targets' residuals (priors excluded)
    metrics: dict  # named simulated numbers (NaN when not computable)
    cached: bool = False  # read from the record, not simulated now


class Record:
    """The evaluations of one context, read from and appended to a JSON-lines file (or only
    kept in memory when ``path`` is None)."""

    def __init__(self, path, context: str):
        self.path = Path(path) if path is not None else None
        self.context = context
        self._known: dict[str, Evaluation] = {}
        self.other_context = 0  # lines of another context (ignored)
        self.skipped = 0  # unreadable lines (a truncated last line)
        self._newline_first = False  # the file ends inside a line (an interrupted write)
        if self.path is not None:
            self._read()

    def _read(self) -> None:
        p = self.path
        if p.exists() and not p.is_file():
            raise UsageError(f"--record {p}: exists and is not a file")
        if not p.exists():
            return
        try:
            text = p.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise UsageError(f"--record {p}: cannot read ({exc})") from None
        self._newline_first = bool(text) and not text.endswith("\n")
        for line in text.splitlines():
            if not line.strip():
                continue
            try:
                d = json.loads(line)
                if d.get("context") != self.context:
                    self.other_context += 1
                    continue
                ev = Evaluation(point=d["point"], residuals=unpack(d["residuals"]),
                                metrics={k: (math.nan if v is None else v) for k, v in d["metrics"].items()},
                                cached=True)
            except (ValueError, KeyError, TypeError, zlib.error):
                self.skipped += 1
                continue
            self._known[point_key(self.context, ev.point)] = ev

    def __len__(self) -> int:
        return len(self._known)

    def get(self, point: dict) -> Evaluation | None:
        ev = self._known.get(point_key(self.context, point))
        if ev is None:
            return None
        return Evaluation(ev.point, ev.residuals, ev.metrics, cached=True)

    def add(self, ev: Evaluation, wall_s: float | None = None) -> None:
        self._known[point_key(self.context, ev.point)] = ev
        if self.path is None:
            return
        line = canonical({"context": self.context, "point": ev.point, "metrics": _json_safe(ev.metrics),
                          "residuals": pack(ev.residuals), "wall_s": wall_s}) + "\n"
        if self.path.parent and not self.path.parent.exists():
            raise UsageError(f"--record {self.path}: its directory does not exist")
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            data = (("\n" if self._newline_first else "") + line).encode("utf-8")
            self._newline_first = False
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
        finally:
            os.close(fd)
