"""SIGTERM (`kill %1`, `timeout`, systemd) ends `wrangler sil` and a scenario as Ctrl-C does. A background job
(`wrangler sil &`) ignores SIGINT, so SIGTERM is how a user stops it: before, Python died at once and left the SIL
firmware running (until its plant timeout) with its temporary flash and key folder behind."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

WRANGLER = [sys.executable, "-c", "from robowrangler.cli.main import entry_point; entry_point()"]


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def test_sigterm_stops_a_background_sil_and_its_firmware(native_build_dir: Path) -> None:
    proc = subprocess.Popen([*WRANGLER, "--json", "sil", "--port", "0", "--unpaced"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=lambda: signal.signal(signal.SIGINT,
                                                                                             signal.SIG_IGN))
    try:
        ready = json.loads(proc.stdout.readline())
        assert ready["type"] == "ready" and not _gone(ready["firmware_pid"])
        proc.send_signal(signal.SIGINT)  # ignored, as in a background job of a shell
        time.sleep(0.5)
        assert proc.poll() is None
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "wrangler: interrupted"
    assert _gone(ready["firmware_pid"])  # stopped and reaped with the session, not left to its plant timeout
    assert "Traceback" not in err


def test_sigterm_during_a_scenario_says_what_it_left(native_build_dir: Path) -> None:
    proc = subprocess.Popen([*WRANGLER, "sil", "--scenario", "mug", "--links", "10"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        lines = []
        while not any("HOME" in line for line in lines):  # the script is running
            line = proc.stderr.readline()
            assert line, "".join(lines)
            lines.append(line)
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130 and out == ""
    left = next(line for line in err.splitlines() if "interrupted in phase" in line)
    assert left.startswith("wrangler: scenario mug interrupted in phase ") and "the SIL firmware is stopped" in left
