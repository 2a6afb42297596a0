"""String-shooter recordings: the real SIL firmware and plants drive the first-principles rope; the MCAP file
reads back with the project's reader and `wrangler inspect`, and its channels agree with each other as a
diagnosis tool needs (the loop flies only once the firmware's telemetry shows the rope above ToV)."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main as wrangler_main
from robowrangler.protocol import generated as gen
from robowrangler.recorder import read_recording
from robowrangler.recorder import schemas_generated as sg
from robowrangler_sim.string_shooter import StringShooterParamError
from robowrangler_sim.string_shooter.recording import RecordingSummary, record_string_shooter
from robowrangler_sim.string_shooter.recording_script import RecordingScript, ScriptCommand

CAMERA_HZ = 30.0
SEED = 11
AIRBORNE_DEPTH_FRACTION = 0.75  # lowest point less than 0.75 x L/2 below the exit: flying (hanging: ~0.95)


@pytest.fixture(scope="module")
def short_run(native_build_dir: Path, tmp_path_factory) -> tuple[Path, RecordingSummary, str]:
    path = tmp_path_factory.mktemp("rec") / "short.mcap"
    progress = io.StringIO()
    summary = record_string_shooter(path, script=RecordingScript.short(), seed=SEED, camera_rate_hz=CAMERA_HZ,
                                    progress=progress)
    return path, summary, progress.getvalue()


def _observations(rec) -> list[dict]:
    return [r.data for r in rec.records["/loop/observation"]]


def _observed_depth_fraction(points_m: list[list[float]]) -> float:
    """Depth of the contour's lowest point below the exit, as a fraction of half the contour's length."""
    p = np.asarray(points_m)
    length_m = float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
    return float(-p[:, 1].min() / (0.5 * length_m))


def test_the_recording_reads_back_and_inspect_exits_0(short_run, tmp_path: Path) -> None:
    path, summary, progress = short_run
    out, err = io.StringIO(), io.StringIO()
    status = wrangler_main(["inspect", str(path), "--json"], Environment(out, err, {}))
    assert status == ExitStatus.OK, err.getvalue()
    inspected = json.loads(out.getvalue())
    rec = read_recording(path)
    assert not rec.truncated
    assert rec.meta["source"] == "sil" and rec.meta["time_base"] == "simulation" and rec.meta["seed"] == str(SEED)
    assert json.loads(rec.metadata["/device/params"]["tov_mps"]) == pytest.approx(2.6)
    counts = {"/device/telemetry": summary.telemetry, "/device/event": summary.events,
              "/host/command": summary.commands, "/loop/observation": summary.observations,
              "/sim/plant_truth": summary.plant_truth}
    assert {k: v for k, v in rec.topic_counts.items() if k in counts} == counts
    assert inspected["channels"] == counts and inspected["gaps"]["count"] == 0
    assert inspected["telemetry"]["states"] == ["DISARMED", "ARMED", "SPINUP", "AIRBORNE", "SPINDOWN", "ARMED"]
    assert "recording short.mcap" in progress and "sim s/wall s" in progress  # progress was shown


def test_channels_and_schemas_are_the_documented_ones(short_run) -> None:
    path, _, _ = short_run
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    by_topic = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
    assert set(by_topic) == {"/device/telemetry", "/device/event", "/host/command", "/loop/observation",
                             "/sim/plant_truth"}  # no /link/gap: nothing was lost
    for topic, schema in by_topic.items():
        name, _, text = sg.CHANNELS[topic]
        assert (schema.name, schema.encoding, schema.data.decode()) == (name, "jsonschema", text)
    for channel in summary.channels.values():
        assert channel.message_encoding == "json"


def test_observations_come_at_the_camera_rate(short_run) -> None:
    path, summary, _ = short_run
    obs = _observations(read_recording(path))
    n = round(CAMERA_HZ * RecordingScript.short().duration_s)
    assert len(obs) == summary.observations == n == 120
    assert [o["frame_index"] for o in obs] == list(range(n))
    assert np.allclose([o["time_s"] for o in obs], np.arange(n) / CAMERA_HZ)
    assert {o["camera_id"] for o in obs} == {"side0"} and all(len(o["points_m"]) == 40 for o in obs)
    assert obs[0]["phi_rad"] == 0.0 and obs[-1]["phi_rad"] == pytest.approx(math.radians(20.0))  # the tilt


def test_the_loop_flies_only_after_the_firmware_rope_passes_tov(short_run) -> None:
    path, summary, _ = short_run
    rec = read_recording(path)
    tov_mps = json.loads(rec.metadata["/device/params"]["tov_mps"])
    tel = rec.telemetry
    above = tel["time_s"][tel["rope_speed_mps"] > tov_mps]
    assert above.size > 50  # the firmware spun the rope well above ToV for a while
    obs = _observations(rec)
    t_obs = np.array([o["time_s"] for o in obs])
    flying = np.array([_observed_depth_fraction(o["points_m"]) < AIRBORNE_DEPTH_FRACTION for o in obs])
    assert flying.sum() > 30  # the camera saw the loop fly ...
    assert not flying[0] and not flying[-1]  # ... and hang before the spin-up and after the spin-down
    first_flying_s = t_obs[flying][0]
    assert first_flying_s > above[0]  # never before the telemetry shows the rope above ToV
    assert summary.first_airborne_s == pytest.approx(first_flying_s)
    # while it flies the rope is above ToV, or was so a moment ago (a loop takes a few tenths of a second to fall)
    for t in t_obs[flying]:
        assert np.any((above <= t) & (above > t - 0.6)), t
    truth = rec.table("/sim/plant_truth")
    assert not truth["loop_airborne"][truth["time_s"] < above[0]].any()


def test_the_nip_follows_the_drive_plant_and_nothing_is_lost(short_run) -> None:
    path, _, _ = short_run
    rec = read_recording(path)
    truth = rec.table("/sim/plant_truth")
    steady = (truth["time_s"] > 1.5) & (truth["time_s"] < 3.0)
    assert np.allclose(truth["rope_speed_mps"][steady], 4.5, atol=0.1)
    assert np.max(np.abs(truth["nip_rope_speed_mps"] - truth["rope_speed_mps"])) < 0.05  # no slip on this run
    assert rec.gaps == [] and not any(rec.telemetry["tx_dropped"])
    assert np.all(np.diff(rec.telemetry["seq"]) > 0) and len(rec.telemetry["seq"]) == 200  # 50 Hz x 4 s
    commands = [(c["message"], c["verdict"]) for c in rec.commands]
    assert commands[:len(gen.PARAMS)] == [("PARAM_GET", "ACK")] * len(gen.PARAMS)
    assert commands[len(gen.PARAMS):] == [("ARM", "ACK"), ("SET_ROPE_SPEED", "ACK"), ("SPINDOWN", "ACK")]
    states = [(e["state_from"], e["state_to"]) for e in rec.events if e["event"] == "STATE_CHANGED"]
    assert states == [("DISARMED", "ARMED"), ("ARMED", "SPINUP"), ("SPINUP", "AIRBORNE"), ("AIRBORNE", "SPINDOWN"),
                      ("SPINDOWN", "ARMED")]


def test_same_seed_same_file_apart_from_the_start_time(short_run, tmp_path: Path) -> None:
    path, _, _ = short_run
    script = RecordingScript(duration_s=1.2, commands=(ScriptCommand(0.6, gen.Arm()),
                                                       ScriptCommand(0.7, gen.SetRopeSpeed(3500))))
    files = []
    for i, seed in enumerate((SEED, SEED, SEED + 1)):
        out = tmp_path / f"{i}.mcap"
        record_string_shooter(out, script=script, seed=seed, camera_rate_hz=CAMERA_HZ)
        created = read_recording(out).meta["created_utc"].encode()
        files.append(out.read_bytes().replace(created, b""))
    assert files[0] == files[1]
    assert files[0] != files[2]  # another seed: other plant and camera noise


def test_bad_arguments_name_the_argument() -> None:
    with pytest.raises(StringShooterParamError, match=r"camera_rate_hz: expected a rate in \[0.5, 1000\] Hz, got 0"):
        record_string_shooter("/nonexistent/x.mcap", camera_rate_hz=0)
    with pytest.raises(StringShooterParamError, match="seed: expected an integer >= 0"):
        record_string_shooter("/nonexistent/x.mcap", seed=-1)
    with pytest.raises(StringShooterParamError, match=r"commands\[1\].at_s: expected non-decreasing"):
        RecordingScript(duration_s=2.0, commands=(ScriptCommand(1.0, gen.Arm()), ScriptCommand(0.5, gen.Arm())))
    with pytest.raises(StringShooterParamError, match=r"commands\[0\].message: expected a protocol command"):
        RecordingScript(duration_s=2.0, commands=(ScriptCommand(0.5, gen.Heartbeat(0)),))
    with pytest.raises(StringShooterParamError, match="phi_rad_points: expected strictly increasing times"):
        RecordingScript(duration_s=2.0, phi_rad_points=((0.0, 0.0), (0.0, 0.1)))


def test_the_spindle_guide_sets_the_rope_loop_length(native_build_dir: Path, tmp_path: Path) -> None:
    # HOME drives the guide from 40 mm to the home end: both strands pay out, the loop grows by 8 cm
    homing_speed = gen.PARAMS_BY_NAME["homing_speed_mmps"].id
    script = RecordingScript(duration_s=7.0, commands=(ScriptCommand(0.5, gen.ParamSet(homing_speed, 7.5)),
                                                       ScriptCommand(0.6, gen.Home())))
    path = tmp_path / "home.mcap"
    record_string_shooter(path, script=script, seed=SEED, read_params=False)
    rec = read_recording(path)
    assert "/device/params" not in rec.metadata
    assert [(e["event"], e["state_to"]) for e in rec.events][-1] == ("SPINDLE_HOMED", "DISARMED")
    assert "HOMED" in rec.telemetry["spindle_flags"][-1]
    truth = rec.table("/sim/plant_truth")
    assert truth["guide_position_m"][0] == pytest.approx(0.040, abs=1e-4)
    assert truth["guide_position_m"][-1] == pytest.approx(0.0, abs=5e-4)
    # the rope's loop follows the spindle plant: 2 m at home, 2 m of rope in per metre of guide travel
    assert np.allclose(truth["loop_length_m"], 2.0 - 2.0 * truth["guide_position_m"], atol=1e-3)
    obs = _observations(rec)
    contour_m = [float(np.sum(np.linalg.norm(np.diff(np.asarray(o["points_m"]), axis=0), axis=1))) for o in obs]
    assert np.mean(contour_m[-10:]) - np.mean(contour_m[:10]) == pytest.approx(0.08, abs=0.02)  # the camera sees it


def test_the_command_line_refuses_bad_input_with_exit_1(tmp_path: Path, capsys) -> None:
    from robowrangler_sim.string_shooter.recording import main

    assert main([str(tmp_path / "x.mcap"), "--camera-rate-hz", "0"]) == 1
    assert "camera_rate_hz: expected a rate in [0.5, 1000] Hz, got 0.0" in capsys.readouterr().err
    assert not (tmp_path / "x.mcap").exists()
