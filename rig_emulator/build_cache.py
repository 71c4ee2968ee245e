"""Results of costly set-up steps kept per process, keyed by what they were built from.

Many runs of one rig in a sweep rebuild the same things (parsed presets, a read calibration
file, the drawn and calibrated sensors). :class:`BuildCache` keeps the last ``size`` of them
(least recently used dropped first) and hands out copies only, so a run that changes what it
got cannot change what the next run gets. A key of None means "not cacheable": the value is
built every time.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Callable, Hashable

from rig_emulator.fast_copy import fast_deepcopy


class BuildCache:
    def __init__(self, size: int, copy: Callable = fast_deepcopy):
        self.size = size
        self._copy = copy
        self._kept: OrderedDict = OrderedDict()

    def get_or_build(self, key: Hashable | None, build: Callable[[], object]):
        """A copy of the value kept under ``key``, or ``build()`` (kept, as a copy, unless the key
        is None; nothing is kept when ``build`` raises)."""
        if key is None:
            return build()
        if key in self._kept:
            self._kept.move_to_end(key)
            return self._copy(self._kept[key])
        value = build()
        self._kept[key] = self._copy(value)
        while len(self._kept) > self.size:
            self._kept.popitem(last=False)
        return value

    def clear(self) -> None:
        self._kept.clear()

    def __len__(self) -> int:
        return len(self._kept)
