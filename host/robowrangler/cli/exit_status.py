"""The `wrangler` exit statuses: one IntEnum, documented in `wrangler --help`."""

from __future__ import annotations

from enum import IntEnum


class ExitStatus(IntEnum):
    """Process exit codes of `wrangler`."""

    OK = 0
    """The command did what was asked."""
    ERROR = 1
    """Anything else that went wrong (link I/O error, state not reached, internal error)."""
    USAGE = 2
    """Bad command line: unknown option, malformed value or URL, unknown parameter, NaN."""
    NACK = 3
    """The device refused the command (NACK); nothing was executed. The reason is on stderr."""
    LINK_TIMEOUT = 4
    """The device did not answer: no telemetry on connect, no ACK after every retry, telemetry stopped."""
    AUTH = 5
    """Link security: no usable key file, a key that does not match the device's, or an unprovisioned device."""
    CTRL_C = 130
    """Interrupted by Ctrl-C (SIGINT)."""
