"""Progress of a reproduction on stderr: a tqdm bar on a terminal, one line per step otherwise."""

from __future__ import annotations

import sys
import threading


class Progress:
    """``update(what)`` after each finished step (thread-safe); ``close()`` at the end."""

    def __init__(self, total: int, stream=None, enabled: bool = True):
        self.total = total
        self.done = 0
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self._lock = threading.Lock()
        self._bar = None
        if enabled and getattr(self.stream, "isatty", lambda: False)():
            try:
                from tqdm import tqdm
            except ImportError:
                tqdm = None
            if tqdm is not None:
                self._bar = tqdm(total=total, file=self.stream, unit="run", desc="reproduce", dynamic_ncols=True)

    def update(self, what: str) -> None:
        with self._lock:
            self.done += 1
            if not self.enabled:
                return
            if self._bar is not None:
                self._bar.set_postfix_str(what, refresh=False)
                self._bar.update(1)
            else:
                print(f"reproduce: [{self.done}/{self.total}] {what}", file=self.stream, flush=True)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
