"""`wrangler proxy --record`: one owner of the link records everything while other tools command through it
(issue 18 item 8). A real SIL firmware (signed link), the proxy in-process, two tools through main(argv, env)."""

from __future__ import annotations

import io
import json
import socket
import threading
import time
from pathlib import Path

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.protocol.generated import Cause
from robowrangler.recorder import read_recording
from robowrangler_sim.sil import SilSession

TEST_KEY = bytes(range(16))


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Runner:
    """`wrangler` in a thread: status, stdout, stderr once joined."""

    def __init__(self, key_file: Path, *argv: str) -> None:
        self.out, self.err = io.StringIO(), io.StringIO()
        self.status: ExitStatus | None = None
        env = Environment(self.out, self.err, {"ROBOWRANGLER_KEY_FILE": str(key_file)})
        self.thread = threading.Thread(target=lambda: setattr(self, "status", main(list(argv), env)), daemon=True)
        self.thread.start()

    def join(self, timeout_s: float = 30.0) -> Runner:
        self.thread.join(timeout_s)
        assert not self.thread.is_alive(), self.err.getvalue()
        return self


def _wait_for_note(runner: Runner, text: str, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while text not in runner.err.getvalue():
        assert time.monotonic() < deadline and runner.thread.is_alive(), runner.err.getvalue()
        time.sleep(0.05)


def test_recording_through_the_proxy_loses_nothing_while_another_tool_commands(native_build_dir: Path,
                                                                               tmp_path: Path, key_file: Path) -> None:
    out = tmp_path / "proxied.mcap"
    port = _free_udp_port()
    tool_url = f"udp://127.0.0.1:{port}"
    with SilSession(speedup=1.0, key=TEST_KEY) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        # the proxy's window is wall time: long enough for every tool below and the device's own landing even on a
        # loaded machine (about 8 s of it is used on an idle one); the assertions count, they do not time
        proxy = Runner(key_file, "--url", sil.cmd_url, "--json", "proxy", "--listen", str(port), "--record", str(out),
                       "--duration", "25")
        _wait_for_note(proxy, "serving udp://127.0.0.1")
        watcher = Runner(key_file, "--url", tool_url, "--json", "watch", "--duration", "4")
        commander = Runner(key_file, "--url", tool_url, "arm").join()
        assert commander.status == ExitStatus.OK, commander.err.getvalue()
        spin = Runner(key_file, "--url", tool_url, "--json", "spin", "4", "--hold", "1.5").join()
        assert spin.status == ExitStatus.OK, spin.err.getvalue() + spin.out.getvalue()[-3000:]
        refused = Runner(key_file, "--url", tool_url, "--json", "param", "set", "guide_max_mm", "0.5").join()
        assert refused.status == ExitStatus.NACK and json.loads(refused.out.getvalue())["reason"] == "OUT_OF_RANGE"
        value = Runner(key_file, "--url", tool_url, "--json", "param", "set", "tov_margin", "1.2").join()
        assert value.status == ExitStatus.OK and json.loads(value.out.getvalue())["value"] == 1.2
        watcher.join()
        # a tool that leaves the rope spinning: the proxy stops heartbeating when no tool is left, so the
        # device lands it by itself (the live-host rule holds through the proxy)
        assert Runner(key_file, "--url", tool_url, "spin", "4").join().status == ExitStatus.OK
        proxy.join(timeout_s=60.0)
    assert proxy.status == ExitStatus.OK, proxy.err.getvalue()
    result = json.loads(proxy.out.getvalue())
    assert result["tools"] >= 5 and result["commands_carried"] >= 6

    watched = [json.loads(line) for line in watcher.out.getvalue().splitlines()]
    telemetry = [w for w in watched if w["type"] == "telemetry"]
    # 50 Hz of the device's time over what the watcher saw (its --duration is wall time: a busy machine paces the
    # SIL slower, so the count over wall time is not the product's behaviour)
    watched_s = telemetry[-1]["time_s"] - telemetry[0]["time_s"] if telemetry else 0.0
    assert watcher.status == ExitStatus.OK and len(telemetry) >= 20, (len(telemetry), watcher.err.getvalue())
    assert len(telemetry) >= 0.8 * 50 * watched_s, (len(telemetry), watched_s)
    assert "AIRBORNE" in {w["state"] for w in telemetry}

    rec = read_recording(out)
    seqs = rec.telemetry["seq"]
    # on the device's clock, as for the watcher: the proxy's window is wall time and a busy machine runs the SIL slower
    span_s = float(rec.telemetry["time_s"][-1] - rec.telemetry["time_s"][0])
    assert len(seqs) >= 0.9 * 50 * span_s and span_s > 3.0, (len(seqs), span_s)  # 50 Hz, not 18
    assert sum(g["missing"] for g in rec.gaps) <= 5, rec.gaps  # loopback UDP: none expected, a few tolerated
    carried = [(c["message"], c["verdict"]) for c in rec.commands if c["message"] not in ("PARAM_GET",)]
    assert ("ARM", "ACK") in carried and ("SET_ROPE_SPEED", "ACK") in carried and ("SPINDOWN", "ACK") in carried
    assert ("PARAM_SET", "NACK") in carried and ("PARAM_SET", "ACK") in carried
    kinds = [(e["event"], e.get("state_to")) for e in rec.events]
    assert ("STATE_CHANGED", "AIRBORNE") in kinds
    landed = [e for e in rec.events if e["event"] == "STATE_CHANGED" and e["state_to"] == "SPINDOWN"]
    assert len(landed) == 2, (rec.events, proxy.err.getvalue())  # the --hold's spindown, then the device's
    assert [e["arg"] for e in landed] == [Cause.COMMAND, Cause.HEARTBEAT_LOST]
    assert rec.telemetry["state"][-1] in ("ARMED", "SPINDOWN")


def test_a_port_in_use_is_a_usage_error_before_the_device_link(tmp_path: Path, key_file: Path) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        run = Runner(key_file, "--url", "udp://127.0.0.1:9", "proxy", "--listen", str(port)).join()
    assert run.status == ExitStatus.USAGE and "--listen: expected a free local UDP port" in run.err.getvalue()
