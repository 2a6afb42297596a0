"""One build at a time per build directory: pytest-xdist workers (and a developer's second pytest) that find the
same CMake tree stale would otherwise run `cmake --build` in it at once."""

from __future__ import annotations

import contextlib
import fcntl
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def exclusive(build_dir: Path) -> Iterator[None]:
    """Hold an exclusive lock on build_dir/.build.lock (created) for the duration of the block."""
    build_dir.mkdir(parents=True, exist_ok=True)
    with open(build_dir / ".build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
