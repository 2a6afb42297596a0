"""SIGTERM ends a long-running command (record, proxy) the way Ctrl-C does: files are finished, the rope lands.

`kill PID`, systemd and `timeout` send SIGTERM; without this, Python dies at once and a recording is left
without its summary and footer (the mcap library then refuses it).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


class Interrupt:
    """What sigterm_as_interrupt() hands its block: `requested` turns true at the first SIGINT or SIGTERM.

    The signal also raises KeyboardInterrupt in the main thread, but Python drops an exception raised while a
    finalizer (__del__, a weakref callback) runs ("Exception ignored in ..."): a loop that checks `requested`
    ends even when its KeyboardInterrupt was lost that way."""

    def __init__(self) -> None:
        self.requested = False

    def check(self) -> None:
        """Raise KeyboardInterrupt if a signal asked to stop (for loops: call once per pass)."""
        if self.requested:
            raise KeyboardInterrupt


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[Interrupt]:
    """While inside, SIGTERM raises KeyboardInterrupt in the main thread (as SIGINT does), and both set the
    yielded Interrupt's `requested` (SIGINT only where Python's own handler had it: not when it is ignored).

    Outside the main thread (signals cannot be handled there) it only yields an Interrupt that stays unset. The
    previous handlers are restored on exit, so that cleanup after the block is not interrupted by this handler
    again.
    """
    stop = Interrupt()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def on_sigterm(_signum: int, _frame: object) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second SIGTERM must not cut the cleanup short
        stop.requested = True
        raise KeyboardInterrupt

    def on_sigint(_signum: int, _frame: object) -> None:
        stop.requested = True
        raise KeyboardInterrupt

    previous_term = signal.signal(signal.SIGTERM, on_sigterm)
    # an ignored SIGINT (a shell's background job) stays ignored; another handler someone set stays theirs
    take_int = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    previous_int = signal.signal(signal.SIGINT, on_sigint) if take_int else None
    try:
        yield stop
    finally:
        signal.signal(signal.SIGTERM, previous_term)
        if take_int:
            signal.signal(signal.SIGINT, previous_int)
