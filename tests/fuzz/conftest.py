"""Fixtures of the fuzz suite: the libFuzzer targets built with clang (skipped when clang is absent)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

# libfuzzer_runner is imported by plain name (pytest's importlib mode does not put test folders on sys.path).
_HERE = str(Path(__file__).resolve().parent)
if _HERE not in sys.path:
    sys.path.insert(0, _HERE)

import libfuzzer_runner  # noqa: E402


@pytest.fixture(scope="session")
def fuzz_build_dir(skip_unless_ci) -> Path:
    """build/fuzz with every fuzz target, built once per session with clang."""
    if libfuzzer_runner.clang_path() is None:
        skip_unless_ci("clang not installed: the libFuzzer targets need clang and its runtime "
                    "(Debian: apt-get install clang libclang-rt-14-dev)")
    return libfuzzer_runner.build()
