"""The ground tools' error types and the exit codes scripts can rely on.

* 0 - the operation succeeded;
* 1 - the operation failed (:class:`OperationError`: no link, timeout, the vehicle rejected
  it, a log without the messages a figure needs);
* 2 - bad usage or bad input (:class:`UsageError`: wrong arguments, a malformed mission file,
  an unreadable log), reported before anything is sent.
"""

from __future__ import annotations

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


class GcsError(Exception):
    exit_code = EXIT_FAILED


class OperationError(GcsError):
    """The operation ran and failed (link, timeout, rejection, missing data)."""

    exit_code = EXIT_FAILED


class UsageError(GcsError):
    """Bad arguments or input; nothing was sent."""

    exit_code = EXIT_USAGE
