"""Typed errors of the SIL: each message says what failed and what to do."""


class SilError(RuntimeError):
    """Base of every SIL failure."""


class SilFirmwareError(SilError):
    """The SIL firmware binary is missing, failed to start, or exited."""


class SilTimeout(SilError):
    """The SIL firmware did not answer a lockstep tick in time."""
