"""Fixtures of the firmware core suite: the core shared library loaded through ctypes."""

from __future__ import annotations

import ctypes
from pathlib import Path

import pytest

import rw_core_ctypes


@pytest.fixture(scope="session")
def rw_core(native_build_dir: Path) -> ctypes.CDLL:
    """librw_core.so of the native build, with the control block signatures declared."""
    return rw_core_ctypes.load(native_build_dir)
