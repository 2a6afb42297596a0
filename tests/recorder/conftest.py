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


TEST_KEY = bytes(range(16))  # the link key the SIL devices of this suite are provisioned with; never a real one


@pytest.fixture
def key_file(tmp_path: Path) -> Path:
    """TEST_KEY in a private key file, as `wrangler --key-file` reads it."""
    path = tmp_path / "link.key"
    path.write_text(TEST_KEY.hex() + "\n")
    path.chmod(0o600)
    return path


@pytest.fixture
def live_sil(native_build_dir: Path) -> Iterator[SilSession]:
    """The SIL firmware + drive plant in real time, past the ESC arming hold, provisioned with TEST_KEY."""
    with SilSession(speedup=1.0, key=TEST_KEY) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        yield sil


@pytest.fixture
def wrangler(key_file: Path) -> Callable[..., tuple[ExitStatus, str, str]]:
    """Run `wrangler ARGV...` in-process with the suite's key file: (exit status, stdout, stderr)."""
    def run(*argv: str) -> tuple[ExitStatus, str, str]:
        out, err = io.StringIO(), io.StringIO()
        status = main(list(argv), Environment(out, err, {"ROBOWRANGLER_KEY_FILE": str(key_file)}))
        return status, out.getvalue(), err.getvalue()
    return run
