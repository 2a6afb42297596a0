"""Fixtures for the host suite: a scripted UDP device on 127.0.0.1 and fast client settings."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

# scripted_device is imported by plain name from the tests of this folder (also under importlib mode).
_HERE = str(Path(__file__).resolve().parent)
if _HERE not in sys.path:
    sys.path.insert(0, _HERE)

from scripted_device import ScriptedDevice  # noqa: E402

# Short timeouts keep the suite fast; the logic under test is the same at any value.
FAST = dict(ack_timeout_s=0.05, retries=3, connect_timeout_s=1.0, heartbeat_hz=20.0)


@pytest.fixture
def device():
    """A running ScriptedDevice (DISARMED, telemetry at 50 Hz, no arming hold)."""
    with ScriptedDevice() as dev:
        yield dev
