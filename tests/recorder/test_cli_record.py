"""`wrangler record / inspect / replay` against the live SIL: a whole recording, link loss, no device,
and kill -9 of a recorder process mid-run.

The recorder is the only host here: the device sends telemetry to the host that sent the last valid frame,
so a recorder next to another commanding host sees only part of the stream (see schema.md)."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.recorder import read_recording
from robowrangler_sim.sil import SilSession

TEST_KEY = bytes(range(16))  # the suite's link key (conftest.py provisions the live SIL with it)

ROOT = Path(__file__).resolve().parents[2]


class _NoteWatch(io.StringIO):
    """A stderr for an in-process `wrangler` that sets `seen` once a note containing `text` is written."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.text, self.seen = text, threading.Event()

    def write(self, s: str) -> int:
        n = super().write(s)
        if self.text in self.getvalue():
            self.seen.set()
        return n


def json_lines(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_record_inspect_replay_on_the_live_device(live_sil: SilSession, tmp_path: Path, wrangler) -> None:
    out = tmp_path / "rec.mcap"
    status, text, err = wrangler("--url", live_sil.cmd_url, "--json", "record", str(out), "--duration", "2",
                                 "--seed", "0")
    assert status == ExitStatus.OK, err
    (summary,) = json_lines(text)
    assert "recording" in err  # progress and notes on stderr, not stdout

    rec = read_recording(out)
    # 50 Hz over the device's own clock (a loaded machine runs the real-time SIL slower than the wall): every
    # frame sent in the recorded span is there or counted in a gap
    span_ms = round(1000 * (rec.telemetry["time_s"][-1] - rec.telemetry["time_s"][0]))
    missing = sum(g["missing"] for g in rec.gaps)
    assert summary["telemetry"] == len(rec.telemetry["seq"]) >= 20
    assert abs(summary["telemetry"] + missing - (span_ms / 20 + 1)) <= 1
    assert rec.meta["source"] == "sil" and rec.meta["seed"] == "0"
    assert float(rec.metadata["/device/params"]["tov_mps"]) == pytest.approx(2.6)
    assert {(c["message"], c["verdict"]) for c in rec.commands} == {("PARAM_GET", "ACK")}  # its parameter reads
    assert len(rec.commands) == len(rec.metadata["/device/params"]) and summary["commands"] == len(rec.commands)
    assert set(rec.telemetry["state"]) == {"DISARMED"}
    # a PARAM_GET per parameter in a row: the device's outbox may drop a telemetry frame for their replies (a gap of 1 each)
    assert all(g["missing"] == 1 for g in rec.gaps) and len(rec.gaps) <= 5

    status, text, err = wrangler("inspect", str(out), "--json")
    assert status == ExitStatus.OK, err
    (info,) = json_lines(text)
    assert info["truncated"] is False and info["channels"]["/device/telemetry"] == len(rec.telemetry["seq"])
    assert info["duration_s"] == pytest.approx(2.0, abs=0.3)
    status, text, _ = wrangler("inspect", str(out))
    assert status == ExitStatus.OK and "/device/telemetry" in text and "gaps:" in text
    png = tmp_path / "plot.png"
    status, _, err = wrangler("replay", str(out), "--plot", str(png))
    assert status == ExitStatus.OK, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_record_survives_link_loss_and_records_the_open_gap(native_build_dir: Path, tmp_path: Path,
                                                            key_file: Path) -> None:
    out = tmp_path / "lost.mcap"
    result = {}
    err = _NoteWatch("recording udp://")
    with SilSession(speedup=1.0, key=TEST_KEY) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        recorder = threading.Thread(target=lambda: result.update(
            status=main(["--url", sil.cmd_url, "--timeout", "0.5", "record", str(out), "--duration", "4",
                         "--no-params"], Environment(io.StringIO(), err, {"ROBOWRANGLER_KEY_FILE": str(key_file)}))))
        recorder.start()
        assert err.seen.wait(timeout=60.0), err.getvalue()  # connected: its first telemetry arrived
        sil.wait_until(sil.time_s + 0.4)  # 0.4 s of the device's time recorded (about 20 frames), then it dies
    recorder.join(timeout=60.0)  # the recorder keeps going to the end of its 4 s
    result["err"] = err.getvalue()
    assert result["status"] == ExitStatus.OK, result["err"]
    assert "link lost" in result["err"]
    rec = read_recording(out)
    assert rec.duration_s > 2.0 and len(rec.telemetry["seq"]) > 10
    (gap,) = rec.gaps
    assert gap["to_seq"] is None and gap["resume_time_s"] is None and gap["silent_s"] > 1.0


def test_record_without_a_device_writes_the_file_and_exits_link_timeout(tmp_path: Path, wrangler) -> None:
    out = tmp_path / "none.mcap"
    t0 = time.monotonic()
    status, _, err = wrangler("--url", "udp://127.0.0.1:9", "--timeout", "0.3", "record", str(out),
                              "--duration", "1")
    assert status == ExitStatus.LINK_TIMEOUT and time.monotonic() - t0 < 3.0
    assert err.splitlines()[-1].startswith("wrangler: no TELEMETRY from udp://127.0.0.1:9")
    rec = read_recording(out)
    assert not rec.truncated and len(rec.telemetry["seq"]) == 0 and rec.meta["source"] == "sil"


def _recorder_process(url: str, out: Path, sig: int, *, lines: int,
                      key_file: Path) -> tuple[subprocess.Popen, list[int], str]:
    """Start `wrangler record` in its own process, wait for `lines` progress lines, send `sig`.

    Returns the process (exited), the telemetry counts of the progress lines, and its stdout."""
    proc = subprocess.Popen(
        [sys.executable, "-c", "from robowrangler.cli.main import entry_point; entry_point()",
         "--url", url, "record", str(out), "--no-params"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
        env={**os.environ, "ROBOWRANGLER_KEY_FILE": str(key_file)},
        # a foreground recorder, as a user at a terminal runs it, even when the suite itself runs as a background
        # job (which inherits an ignored SIGINT; the recorder rightly keeps an ignored SIGINT ignored)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    progress = []  # "wrangler: killed.mcap:    2.0 s, 100 telemetry, ..." every 2 s
    try:
        for line in proc.stderr:
            if "telemetry," in line:
                progress.append(int(line.split(" telemetry,")[0].rsplit(" ", 1)[1]))
                if len(progress) == lines:
                    break
    finally:
        proc.send_signal(sig)
        stdout, _ = proc.communicate(timeout=60)  # a hang guard only: a loaded machine is slow to finish
    return proc, progress, stdout


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_ctrl_c_and_sigterm_finish_the_file_for_any_mcap_reader(live_sil: SilSession, tmp_path: Path,
                                                                 key_file: Path, sig: int) -> None:
    """`kill PID` (SIGTERM) ends a recording as Ctrl-C does: summary and footer written, the mcap library's
    indexed reader opens it, the chunks are zstd."""
    from mcap.reader import make_reader

    out = tmp_path / "stopped.mcap"
    proc, progress, stdout = _recorder_process(live_sil.cmd_url, out, sig, lines=1, key_file=key_file)
    assert proc.returncode == ExitStatus.OK and "recorded" in stdout
    rec = read_recording(out)
    assert not rec.truncated and len(rec.telemetry["seq"]) >= progress[-1]
    with open(out, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and {ci.compression for ci in summary.chunk_indexes} == {"zstd"}
        telemetry = sum(1 for _ in reader.iter_messages(topics=["/device/telemetry"]))
    assert telemetry == len(rec.telemetry["seq"])


def test_record_refuses_an_existing_file_unless_forced_and_a_non_mcap_name(tmp_path: Path, wrangler) -> None:
    existing = tmp_path / "run.mcap"
    existing.write_bytes(b"precious")
    status, out, err = wrangler("--url", "udp://127.0.0.1:9", "record", str(existing), "--duration", "0.2")
    assert status == ExitStatus.USAGE and out == "" and "add --force to replace it" in err
    assert existing.read_bytes() == b"precious"
    status, _, err = wrangler("--url", "udp://127.0.0.1:9", "--timeout", "0.1", "record", str(existing),
                              "--duration", "0.2", "--force")
    assert status == ExitStatus.LINK_TIMEOUT and read_recording(existing).meta["source"] == "sil"
    status, _, err = wrangler("--url", "udp://127.0.0.1:9", "record", str(tmp_path / "run.csv"))
    assert status == ExitStatus.USAGE and "ending in .mcap" in err and not (tmp_path / "run.csv").exists()
    for bad in ("nan", "inf", "-1", "0"):
        status, _, err = wrangler("--url", "udp://127.0.0.1:9", "record", str(tmp_path / "d.mcap"), "--duration", bad)
        assert status == ExitStatus.USAGE and "--duration" in err, (bad, err)
    assert not (tmp_path / "d.mcap").exists()


def test_kill_9_mid_recording_leaves_every_chunk_but_the_last(live_sil: SilSession, tmp_path: Path, key_file: Path,
                                                              wrangler) -> None:
    out = tmp_path / "killed.mcap"
    proc, progress, _ = _recorder_process(live_sil.cmd_url, out, signal.SIGKILL, lines=2, key_file=key_file)
    assert proc.returncode == -signal.SIGKILL
    written = progress[-1]  # telemetry the recorder had written when it printed the line
    rec = read_recording(out)
    got = len(rec.telemetry["seq"])
    assert rec.truncated and ("cut off" in rec.truncation_reason or "no footer" in rec.truncation_reason)
    # at most one unfinished chunk (<= 0.5 s = 25 frames at 50 Hz) is lost; a few more may have come after the line
    assert written - 30 <= got <= written + 15, (written, got)
    assert rec.telemetry["seq"].tolist() == sorted(rec.telemetry["seq"].tolist())
    status, text, err = wrangler("inspect", str(out))
    assert status == ExitStatus.OK and "TRUNCATED" in text and "truncated" in err
