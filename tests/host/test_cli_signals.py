"""Ctrl-C and SIGTERM end the long-running verbs (record, proxy, sil) even when Python drops the KeyboardInterrupt:
an exception raised while a finalizer runs is only printed ("Exception ignored in ..."), so the loops also check
the flag the signal sets."""

from __future__ import annotations

import os
import signal
import time

import pytest

from robowrangler.cli.signals import sigterm_as_interrupt


class _SignalledWhileFinalized:
    """Its finalizer is where the signal lands: the KeyboardInterrupt raised there is dropped by Python."""

    def __init__(self, sig: int) -> None:
        self.sig = sig

    def __del__(self) -> None:
        os.kill(os.getpid(), self.sig)
        time.sleep(0.05)  # the handler runs here, inside the finalizer


@pytest.fixture
def foreground_sigint():
    """Ctrl-C as at a terminal, even when the suite runs as a shell's background job (SIGINT ignored there)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.usefixtures("foreground_sigint")
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # the dropped interrupt
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_whose_interrupt_python_dropped_still_stops_the_loop(sig: int) -> None:
    passes = 0
    with pytest.raises(KeyboardInterrupt):
        with sigterm_as_interrupt() as stop:
            obj = _SignalledWhileFinalized(sig)
            del obj  # the KeyboardInterrupt is raised in __del__ and dropped: the block goes on
            while passes < 1000:
                stop.check()
                passes += 1
    assert passes == 0 and stop.requested


@pytest.mark.usefixtures("foreground_sigint")
def test_handlers_are_restored_after_the_block() -> None:
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    with sigterm_as_interrupt() as stop:
        assert signal.getsignal(signal.SIGINT) is not before[0]
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before and not stop.requested


def test_an_ignored_sigint_stays_ignored() -> None:
    """A background job of a shell ignores Ctrl-C's SIGINT; only SIGTERM ends it."""
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with sigterm_as_interrupt() as stop:
            assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
            stop.check()
        assert not stop.requested and signal.getsignal(signal.SIGINT) == signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)
