"""`wrangler excite` against a running SIL device (real time, real signed UDP), as a user runs it: the run follows
the profile, lands the rope, and leaves a recording the reader validates, with the bursts complete; profiles that
leave what the device allows are refused with a reason before anything moves."""

from __future__ import annotations

import io
import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.client import Client
from robowrangler.recorder import read_recording
from robowrangler.recorder.burst import bursts
from robowrangler.recorder.encoder_period import mt_period_us
from robowrangler_sim.sil import SilSession


@pytest.fixture
def live_sil(native_build_dir: Path) -> Iterator[SilSession]:
    with SilSession(speedup=1.0) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)  # past the ESC arming hold
        yield sil


def wrangler(sil: SilSession | None, *argv: str) -> tuple[ExitStatus, list[dict], str]:
    out, err = io.StringIO(), io.StringIO()
    prefix: list[str] = []
    if sil is not None:
        key_file = Path(sil.state_file).with_name("link.key")
        key_file.write_text(sil.key.hex() + "\n")
        key_file.chmod(0o600)
        prefix = ["--url", sil.cmd_url, "--key-file", str(key_file)]
    status = main([*prefix, "--json", *argv], Environment(out, err, {}))
    return status, [json.loads(line) for line in out.getvalue().splitlines() if line.strip()], err.getvalue()


def test_excite_runs_the_quick_profile_and_records_it(live_sil: SilSession, tmp_path: Path) -> None:
    out = tmp_path / "quick.mcap"
    status, lines, err = wrangler(live_sil, "excite", "--profile", "quick", "--out", str(out))
    assert status == ExitStatus.OK, err
    result = lines[-1]
    assert (result["steps"], result["bursts"], result["burst_frames_missing"]) == (6, 2, 0)
    assert result["final_state"] == "DISARMED"
    rec = read_recording(out)  # validates every message against its channel's schema
    assert rec.meta["source"] == "sil" and not rec.truncated
    assert "/device/params" in rec.metadata and rec.metadata["/excite/profile"]["name"] == "quick"
    speeds = [c["fields"].get("rope_speed_mps") for c in rec.commands if c["message"] == "SET_ROPE_SPEED"]
    assert speeds[0] == 4.0 and 5.0 in speeds and len(speeds) > 20, "the chirp's setpoints were sent"
    assert all(c["verdict"] == "ACK" for c in rec.commands)
    got = bursts(rec)
    assert [(b.sample_count, b.complete) for b in got] == [(300, True), (200, True)]
    states = {e["state_to"] for e in rec.events if e["event"] == "STATE_CHANGED"}
    assert {"AIRBORNE", "SPINDOWN", "ARMED", "DISARMED"} <= states
    # the raw encoder period from telemetry (M/T between frames) agrees with the filtered speed while flying
    tel = rec.telemetry
    period_us = mt_period_us(tel["encoder_counts"], tel["encoder_edge_us"])
    flying = (tel["rope_speed_mps"] > 3.5) & np.isfinite(period_us)
    implied_mps = 2 * np.pi * 0.015 / (64 * period_us[flying] * 1e-6)
    assert flying.sum() > 20
    assert np.median(np.abs(implied_mps / tel["rope_speed_mps"][flying] - 1)) < 0.02


def test_a_profile_beyond_the_devices_limits_is_refused_before_anything_moves(live_sil: SilSession,
                                                                             tmp_path: Path) -> None:
    with Client(live_sil.cmd_url, key=live_sil.key) as rw:
        rw.set_param("max_rope_speed_mps", 6.0)
    profile = tmp_path / "fast.toml"
    profile.write_text('[[step]]\nkind = "speed"\nspeed_mps = 8.0\nhold_s = 1.0\n')
    out = tmp_path / "fast.mcap"
    status, lines, err = wrangler(live_sil, "excite", "--profile", str(profile), "--out", str(out))
    assert status == ExitStatus.USAGE
    assert "max_rope_speed_mps 6" in err and "step 1 (speed).speed_mps" in err
    rec = read_recording(out)
    assert not [c for c in rec.commands if c["message"] in ("ARM", "SET_ROPE_SPEED")], "nothing was commanded"
    assert "/device/params" in rec.metadata


@pytest.mark.parametrize(("text", "says"), [
    ('[[step]]\nkind = "speed"\nspeed_mps = 2.0\nhold_s = 1.0\n', "ToV guard 2.990 m/s"),
    ('[[step]]\nkind = "chirp"\ncenter_mps = 4.0\namplitude_mps = 1.5\nf0_hz = 0.1\nf1_hz = 1.0\nduration_s = 2\n',
     "center_mps - amplitude_mps"),
    ('[[step]]\nkind = "jump"\n', "kind: expected one of speed"),
])
def test_bad_profiles_are_refused_without_a_device(tmp_path: Path, text: str, says: str) -> None:
    profile = tmp_path / "bad.toml"
    profile.write_text(text)
    status, lines, err = wrangler(None, "--url", "udp://127.0.0.1:9", "excite", "--profile", str(profile),
                                  "--out", str(tmp_path / "x.mcap"))
    assert status == ExitStatus.USAGE and says in err, err
    assert lines[-1]["error"] == "ProfileError"
    assert not (tmp_path / "x.mcap").exists(), "refused before any recording or link"


def test_an_unknown_profile_names_the_shipped_ones(tmp_path: Path) -> None:
    status, lines, err = wrangler(None, "excite", "--profile", "nosuch", "--out", str(tmp_path / "x.mcap"))
    assert status == ExitStatus.USAGE
    assert "--profile: expected one of drive, quick, spindle, standard or a .toml file, got 'nosuch'" in err
