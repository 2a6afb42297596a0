"""`wrangler record` attached to an unpaced SIL (simulated time running as fast as the machine goes): the
recording holds the device's telemetry in order, every frame (no gap), its parameters, and validates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robowrangler.cli.exit_status import ExitStatus
from robowrangler.recorder import read_recording
from robowrangler_sim.sil import SilSession

TEST_KEY = bytes(range(16))


def test_record_attaches_to_an_unpaced_sil(native_build_dir: Path, tmp_path: Path, wrangler) -> None:
    out = tmp_path / "unpaced.mcap"
    with SilSession(speedup=None, key=TEST_KEY) as sil:
        sil.run_in_background()
        status, stdout, err = wrangler("--url", sil.cmd_url, "--json", "record", str(out), "--duration", "2")
        device_s = sil.time_s
    assert status == ExitStatus.OK, err
    rec = read_recording(out)
    t = rec.telemetry["time_s"]
    assert len(t) > 50 and np.all(np.diff(t) > 0), "device time in order"
    assert not rec.gaps, "no frame lost"
    assert rec.meta["source"] == "sil" and "/device/params" in rec.metadata
    assert t[-1] <= device_s
    periods = np.diff(t)
    assert np.median(periods) == pytest.approx(0.02), "the device's own 50 Hz, whatever the wall clock does"
