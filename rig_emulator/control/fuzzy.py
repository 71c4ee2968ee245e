"""Moved to :mod:`rig_emulator.controllers.builtin.fuzzy` (the built-in laws live beside the
controller interface and its examples); this name stays importable: it is that very module."""

import sys

from rig_emulator.controllers.builtin import fuzzy as _module

sys.modules[__name__] = _module
