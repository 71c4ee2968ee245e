"""A command-line tool whose reader went away (``rig-emulator params | head``) stops quietly.

Python raises BrokenPipeError on the next write to a closed pipe, and once more when it
flushes stdout at exit (a second traceback). :func:`quiet_exit_on_closed_pipe` points stdout
at /dev/null so the exit flush succeeds, and gives the exit status a shell gives a tool
killed by SIGPIPE (128 + 13), as ``head``'s other writers (``yes``, ``cat``) end.
"""

from __future__ import annotations

import os
import sys

CLOSED_PIPE_EXIT = 141  # 128 + SIGPIPE


def quiet_exit_on_closed_pipe() -> int:
    """Call from ``except BrokenPipeError``: silence stdout for the exit flush; return 141."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass  # stdout has no file descriptor (captured): nothing left to flush into the pipe
    return CLOSED_PIPE_EXIT
