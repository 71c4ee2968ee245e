"""The rig's state directory: where parameters, the mission and the signing clock survive a restart.

``rig-emulator serve`` keeps its state in ``./rig-state`` (``--state-dir DIR`` elsewhere,
``--no-persist`` nowhere), as ArduPilot's SITL keeps ``eeprom.bin`` in its working
directory. The directory holds small JSON documents (:mod:`~rig_emulator.link.parameters.store`,
:mod:`~rig_emulator.link.mission.store`, :mod:`~rig_emulator.link.state.rig_state`), each with a ``format`` name and a ``version``.

* **Atomic writes.** Every document is written whole to a temporary file in the directory,
  synced, renamed over the old one and the directory synced
  (:func:`protocol.atomic_file.atomic_path`): a rig killed at any moment leaves the old
  document or the new one, never a mix. Temporary files a killed rig left behind are
  removed on the next start.
* **One rig per directory.** The rig holds an exclusive ``flock`` on ``DIR/lock`` while it
  runs (the kernel drops it when the process dies, even by SIGKILL); a second rig on the
  same directory stops with an error naming the directory and the holder's pid.
* **No silent reset.** A document that cannot be read (bad JSON, another format, an unknown
  version, a value out of range) stops the start with :class:`StateError` naming the file
  (exit code 2); ``--wipe`` discards the stored state instead.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from protocol.atomic_file import atomic_write_text
from rig_emulator.config.loader import ConfigError

DEFAULT_STATE_DIR = "rig-state"
LOCK_NAME = "lock"
HINT = "fix or delete it, or start with --wipe to discard the stored state"


class StateError(ConfigError):
    """A state directory or document the rig cannot start with (exit code 2)."""


class StateWriteError(ValueError):
    """A document could not be stored; what was stored before is unchanged."""


def _no_constant(name: str):
    raise ValueError(f"{name} is not valid JSON")


class StateDir:
    """An open, locked state directory (close it to release the lock)."""

    def __init__(self, path):
        self.path = Path(path)
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StateError(f"state directory {self.path}: cannot create it: {exc.strerror}") from None
        if not self.path.is_dir():
            raise StateError(f"state directory {self.path}: not a directory")
        self._lock_fd = self._lock()
        self._remove_stale_temporaries()

    def _lock(self) -> int | None:
        try:
            import fcntl
        except ImportError:  # not POSIX: no locking
            return None
        lock_path = self.path / LOCK_NAME
        try:
            fd = os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise StateError(f"state directory {self.path}: cannot open {lock_path}: {exc.strerror}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.read(fd, 32).decode("ascii", "replace").strip() or "?"
            os.close(fd)
            raise StateError(f"state directory {self.path} is in use by another rig (pid {holder}); "
                             "give each rig its own --state-dir, or use --no-persist") from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        return fd

    def _remove_stale_temporaries(self) -> None:
        for tmp in self.path.glob(".*.tmp"):
            try:
                tmp.unlink()
            except OSError:
                pass

    def file(self, name: str) -> Path:
        return self.path / name

    def read_json(self, name: str, fmt: str, version: int):
        """The document ``name`` (None when absent); StateError naming the file when unusable."""
        path = self.file(name)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise StateError(f"{path}: cannot read: {exc.strerror}; {HINT}") from None
        try:
            doc = json.loads(data.decode("utf-8"), parse_constant=_no_constant)
        except UnicodeDecodeError:
            raise StateError(f"{path}: not UTF-8 text; {HINT}") from None
        except json.JSONDecodeError as exc:
            raise StateError(f"{path}:{exc.lineno}: invalid JSON: {exc.msg} (column {exc.colno}); {HINT}") from None
        except ValueError as exc:
            raise StateError(f"{path}: invalid JSON: {exc}; {HINT}") from None
        if not isinstance(doc, dict) or doc.get("format") != fmt:
            raise StateError(f"{path}: not a {fmt!r} document (its \"format\" must be {fmt!r}); {HINT}")
        if doc.get("version") != version:
            raise StateError(f"{path}: unsupported version {json.dumps(doc.get('version'))}, expected {version}; {HINT}")
        return doc

    def error(self, name: str, where: str, reason: str) -> StateError:
        """A StateError for a value in document ``name``."""
        return StateError(f"{self.file(name)}: {where}: {reason}; {HINT}")

    def write_json(self, name: str, doc: dict) -> None:
        """Store ``doc`` atomically; StateWriteError (old document intact) when it cannot be."""
        text = json.dumps(doc, indent=1, sort_keys=True, allow_nan=False) + "\n"
        try:
            atomic_write_text(self.file(name), text)
        except OSError as exc:
            raise StateWriteError(f"cannot store {self.file(name)}: {exc.strerror or exc}") from None

    def remove(self, name: str) -> bool:
        """Delete document ``name``; True if there was one."""
        try:
            self.file(name).unlink()
        except FileNotFoundError:
            return False
        except OSError as exc:
            raise StateError(f"{self.file(name)}: cannot remove: {exc.strerror}") from None
        return True

    def close(self) -> None:
        if self._lock_fd is not None:
            os.close(self._lock_fd)  # releases the flock
            self._lock_fd = None
