"""SIL fixtures: a fresh firmware process + drive plant per test, driven by a deterministic scripted host."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost


@pytest.fixture
def host(native_build_dir: Path) -> Iterator[ScriptedHost]:
    """A scripted host on an unpaced SIL, past the ESC arming hold (0.6 s simulated)."""
    with SilSession(speedup=None) as sil:
        h = ScriptedHost(sil)
        h.run_for(0.6)
        yield h
        h.close()
