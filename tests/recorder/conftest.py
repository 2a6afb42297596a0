"""Recorder fixtures: a live SIL device (real time, UDP) and a runner for `wrangler` in-process."""

from __future__ import annotations

import io
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler_sim.sil import SilSession


@pytest.fixture
def live_sil(native_build_dir: Path) -> Iterator[SilSession]:
    """The SIL firmware + drive plant in real time, past the ESC arming hold."""
    with SilSession(speedup=1.0) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        yield sil


@pytest.fixture
def wrangler() -> Callable[..., tuple[ExitStatus, str, str]]:
    """Run `wrangler ARGV...` in-process: (exit status, stdout, stderr)."""
    def run(*argv: str) -> tuple[ExitStatus, str, str]:
        out, err = io.StringIO(), io.StringIO()
        status = main(list(argv), Environment(out, err, {}))
        return status, out.getvalue(), err.getvalue()
    return run
