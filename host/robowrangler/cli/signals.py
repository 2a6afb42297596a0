"""SIGTERM ends a long-running command (record, proxy) the way Ctrl-C does: files are finished, the rope lands.

`kill PID`, systemd and `timeout` send SIGTERM; without this, Python dies at once and a recording is left
without its summary and footer (the mcap library then refuses it).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """While inside, SIGTERM raises KeyboardInterrupt in the main thread (as SIGINT does).

    Outside the main thread (signals cannot be handled there) it does nothing. The previous handler is
    restored on exit, so that cleanup after the block is not interrupted by this handler again.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(_signum: int, _frame: object) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second SIGTERM must not cut the cleanup short
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
