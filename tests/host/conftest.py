"""Fixtures for the host suite: the real firmware core as the device (core_device.py) and fast client settings."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

# core_device (here) and core_harness, rw_core_ctypes (the firmware core suite's) are imported by plain name from
# the tests of this folder (also under importlib mode).
# This folder goes first (its `conftest` is the one the tests import FAST from), the core suite's last.
_HERE = Path(__file__).resolve().parent
if str(_HERE) in sys.path:
    sys.path.remove(str(_HERE))
sys.path.insert(0, str(_HERE))
if str(_HERE.parent / "firmware_core") not in sys.path:
    sys.path.append(str(_HERE.parent / "firmware_core"))

import rw_core_ctypes  # noqa: E402
from core_device import CoreDevice  # noqa: E402

# Short timeouts keep the suite fast; the logic under test is the same at any value.
FAST = dict(ack_timeout_s=0.05, retries=3, connect_timeout_s=1.0, heartbeat_hz=20.0)
QUICK_ARM = {"arm_hold_s": 0.2}  # the shortest ESC arming hold the core takes


@pytest.fixture(scope="session")
def core_lib(native_build_dir: Path):
    """librw_core.so of the native build."""
    return rw_core_ctypes.load(native_build_dir)


@pytest.fixture
def device(core_lib):
    """The core on its WiFi link (key TEST_KEY), real-time paced, arming hold 0.2 s."""
    with CoreDevice(core_lib, params=QUICK_ARM) as dev:
        yield dev
