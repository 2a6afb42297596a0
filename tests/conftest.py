"""Session fixtures shared by every suite: the native firmware build (core library, SIL executable)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

if str(Path(__file__).resolve().parent) not in sys.path:  # tests/build_lock.py for the build helpers below
    sys.path.insert(0, str(Path(__file__).resolve().parent))

from build_lock import exclusive  # noqa: E402

REPO_ROOT = Path(__file__).resolve().parents[1]
BUILD_DIR = Path(os.environ.get("ROBOWRANGLER_BUILD_DIR", REPO_ROOT / "build" / "native"))


def build_native() -> Path:
    """Configure and build firmware/ natively with CMake (incremental); returns the build directory."""
    with exclusive(BUILD_DIR):
        if not (BUILD_DIR / "CMakeCache.txt").exists():
            subprocess.run(["cmake", "-S", str(REPO_ROOT / "firmware"), "-B", str(BUILD_DIR)],
                           check=True, capture_output=True, text=True)
        result = subprocess.run(["cmake", "--build", str(BUILD_DIR), "-j2"], capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"native firmware build failed:\n{result.stdout}\n{result.stderr}")
    return BUILD_DIR


@pytest.fixture(scope="session")
def native_build_dir() -> Path:
    """The native build directory, built once per test session."""
    return build_native()


def _skip_unless_ci(reason: str) -> None:
    if os.environ.get("CI") == "true":
        pytest.fail(f"{reason} (CI=true: scripts/setup.sh installs it, so its absence is a failure)")
    pytest.skip(reason)


@pytest.fixture(scope="session")
def skip_unless_ci():
    """skip_unless_ci(reason): skip a test whose tool or toolchain is missing on a developer's machine; in CI
    (CI=true), where scripts/setup.sh installs every tool, the same absence fails the test, never a silent skip."""
    return _skip_unless_ci
