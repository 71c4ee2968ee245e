"""Moved to :mod:`rig_emulator.controllers.builtin.fuzzy_surface` (the built-in laws live beside the
controller interface and its examples); this name stays importable: it is that very module."""

import sys

from rig_emulator.controllers.builtin import fuzzy_surface as _module

sys.modules[__name__] = _module
