"""Fixtures for the host suite: the real firmware core as the device (core_device.py) and fast client settings."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

# The helpers of this folder (core_device, host_settings, wire) and of the core suite (core_harness,
# rw_core_ctypes) are imported by plain name from the tests (also under importlib mode); their names are unique.
_HERE = Path(__file__).resolve().parent
for _folder in (str(_HERE), str(_HERE.parent / "firmware_core")):
    if _folder not in sys.path:
        sys.path.insert(0, _folder)

import rw_core_ctypes  # noqa: E402
from core_device import CoreDevice  # noqa: E402
from host_settings import QUICK_ARM  # noqa: E402


@pytest.fixture(scope="session")
def core_lib(native_build_dir: Path):
    """librw_core.so of the native build."""
    return rw_core_ctypes.load(native_build_dir)


@pytest.fixture
def device(core_lib):
    """The core on its WiFi link (key TEST_KEY), real-time paced, arming hold 0.2 s."""
    with CoreDevice(core_lib, params=QUICK_ARM) as dev:
        yield dev
