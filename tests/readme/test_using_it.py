"""The README's "Using it" block, run top to bottom with bash on a fresh HOME (issue 18).

What is changed, and only this: `uv run wrangler` is the wrangler of this environment (a fresh HOME has no
uv cache to resolve from); the ports 14550/14551 become free ones (the suite runs beside other SILs), with
ROBOWRANGLER_URL pointing at the first as the default URL does; two lines are not run, named below with why.
Every other line runs as written, under `set -e`: a failing command fails the test.
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from robowrangler.recorder import read_recording

ROOT = Path(__file__).resolve().parents[2]
NOT_RUN = {  # README line -> why this test does not run it
    "uv run wrangler sil --scenario tennis_ball --render out/ball":
        "a whole MuJoCo wrangle (minutes); tests/sil_chain runs the scenarios",
    "uv run wrangler sil --scenario door_handle --viewer": "opens MuJoCo's viewer window: needs a display",
    "uv run wrangler identify photos/manifest.json --out my_table.json":
        "needs the user's photos of the flying loop; tests/sim_identify runs identify on synthetic photos",
}


def _using_it_block() -> list[str]:
    text = (ROOT / "README.md").read_text()
    section = text.split("## Using it", 1)[1]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    return [line for line in block.splitlines() if line.strip()]


def _free_udp_ports(n: int) -> list[int]:
    socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(n)]
    try:
        for s in socks:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


@pytest.mark.slow  # about 80 s of real time (homing alone is 15 s); `-m "not slow"` leaves it out
def test_the_readme_using_it_block_runs_top_to_bottom_on_a_fresh_home(native_build_dir: Path, tmp_path: Path) -> None:
    lines = _using_it_block()
    commands = [line.split("  #")[0].rstrip() for line in lines]
    assert set(NOT_RUN) <= set(commands), "a line this test skips is no longer in the README: update NOT_RUN"
    device_port, proxy_port = _free_udp_ports(2)
    # on any exit (a failing line under set -e too) the background jobs go with the shell, so that their open
    # pipes never keep this test waiting past the failure it should report
    script = ["set -euo pipefail", "set -x", "set -m", "trap 'kill $(jobs -p) 2>/dev/null || true' EXIT",
              f"export ROBOWRANGLER_URL=udp://127.0.0.1:{device_port}"]
    for command in commands:
        if command in NOT_RUN:
            script.append(f": not run: {command}")
            continue
        command = command.replace("uv run wrangler", "wrangler")
        command = command.replace("14550", str(device_port)).replace("14551", str(proxy_port))
        script.append(command)
    script.append("kill %1; wait %1 || true")  # the SIL started in the first lines
    home = tmp_path / "home"
    home.mkdir()
    work = tmp_path / "work"
    work.mkdir()
    bin_dir = str(Path(sys.executable).parent)
    assert shutil.which("wrangler", path=bin_dir), "the wrangler console script of this environment"
    env = {"HOME": str(home), "PATH": f"{bin_dir}:{os.environ['PATH']}", "LANG": "C.UTF-8",
           "ROBOWRANGLER_BUILD_DIR": str(native_build_dir)}
    run = subprocess.run(["bash", "-c", "\n".join(script)], cwd=work, env=env, capture_output=True, text=True,
                         timeout=240)
    assert run.returncode == 0, run.stderr[-4000:]
    key = home / ".config" / "robowrangler" / "link.key"
    assert oct(key.stat().st_mode & 0o777) == "0o600" and len(bytes.fromhex(key.read_text().strip())) == 16
    assert "held 4 m/s for 5 s, spun down (state ARMED)" in run.stdout
    assert re.search(r"guide at 59\.\d+ mm \(target 60 mm|guide at 60(\.\d+)? mm \(target 60 mm", run.stdout), run.stdout
    assert "drive_resistance_ohm" in run.stdout  # param list ran (its last row)
    assert "emergency stop (state ESTOP)" in run.stdout
    recorded = read_recording(work / "run.mcap")
    assert len(recorded.telemetry["seq"]) >= 400 and not recorded.truncated
    session = read_recording(work / "session.mcap")
    assert not session.truncated and len(session.telemetry["seq"]) >= 0.9 * 50 * session.duration_s
    assert {c["message"] for c in session.commands} >= {"SET_ROPE_SPEED", "SPINDOWN"}
