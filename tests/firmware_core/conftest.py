"""Fixtures of the firmware core suite: the core shared library loaded through ctypes."""

from __future__ import annotations

import ctypes
import sys
from pathlib import Path

import pytest

# The helper modules of this suite (rw_core_ctypes, sim_encoder) are imported by plain name: make
# that work under pytest's importlib import mode too, where test folders are not put on sys.path.
_HERE = str(Path(__file__).resolve().parent)
if _HERE not in sys.path:
    sys.path.insert(0, _HERE)

import rw_core_ctypes  # noqa: E402


@pytest.fixture(scope="session")
def rw_core(native_build_dir: Path) -> ctypes.CDLL:
    """librw_core.so of the native build, with the control block signatures declared."""
    return rw_core_ctypes.load(native_build_dir)
