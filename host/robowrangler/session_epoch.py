"""The session epoch a host hands the device at every provisioning commit (PROVISION_COMMIT.session_epoch).

The device's session id is session_epoch + boot counter (firmware/core/rw_config.h). A firmware upload erases
the flash and with it the boot counter; a fresh random epoch at the next provisioning puts that provisioning's
session ids at a random place in [0, 2^32), so frames recorded under an earlier provisioning with the same key
are refused as replays. The epoch is 31 bits (0 <= epoch < 2^31) so that epoch + boot counter (< 2^31)
never wraps: within a provisioning the session ids grow strictly.
"""

from __future__ import annotations

import os
from collections.abc import Callable

EPOCH_LIMIT = 1 << 31
"""session_epoch must be under this (the device answers OUT_OF_RANGE otherwise)."""


def new_session_epoch(*, random_bytes: Callable[[int], bytes] = os.urandom) -> int:
    """A uniformly random epoch in [0, 2^31) from the OS CSPRNG (random_bytes(n) -> n bytes; injectable for tests)."""
    raw = random_bytes(4)
    if not isinstance(raw, (bytes, bytearray)) or len(raw) != 4:
        raise ValueError(f"random_bytes: expected a function returning 4 bytes, got {raw!r}")
    return int.from_bytes(raw, "little") & (EPOCH_LIMIT - 1)


__all__ = ["EPOCH_LIMIT", "new_session_epoch"]
