"""Headless runs for the command line: streamed in chunks, series written as they come.

Kept outside the compiled packages (``rig_emulator/_jit.py`` ``COMPILED_ROOTS``) so that
editing it does not invalidate numba's cache of the step loop.
"""
