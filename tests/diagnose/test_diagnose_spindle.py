"""The spindle half of wrangler diagnose on short generated recordings: the fast plant against the per-tick one,
each spindle candidate recovered, an effect-free recording gives none, a recording without spindle motion reports
the spindle effects as not testable, the model file carries the terms into the SIL's spindle plant."""

from __future__ import annotations

import json

import numpy as np
import pytest

from robowrangler_sim.diagnose import diagnose
from robowrangler_sim.diagnose.candidates.screw_backlash import ScrewBacklash
from robowrangler_sim.diagnose.candidates.servo_deadband import ServoDeadband
from robowrangler_sim.diagnose.model_file import load_model
from robowrangler_sim.diagnose.proof.spindle_generator import generate_spindle_recording
from robowrangler_sim.diagnose.report import write_report
from robowrangler_sim.diagnose.spindle_stage import diagnose_spindle
from robowrangler_sim.plants import spindle_batch as sb
from robowrangler_sim.plants.spindle import SpindleInputs, SpindleParams, SpindlePlant

SPINDLE = [ScrewBacklash(), ServoDeadband()]


@pytest.mark.parametrize("terms", [{}, {"servo_deadband_raw": 80.0, "servo_deadband_hysteresis_raw": 20.0},
                                   {"screw_backlash_mm": 0.8}])
def test_batched_spindle_matches_the_per_tick_plant(terms):
    rng = np.random.default_rng(1)
    raw = np.zeros(3000, dtype=np.int64)
    k = 0
    while k < raw.size:
        n = int(rng.integers(100, 400))
        raw[k:k + n] = int(rng.integers(0, 700)) | (0x400 if rng.random() < 0.5 else 0)
        k += n
    p = SpindleParams(position_noise_units=0.0, load_noise_permille=0.0, **terms)
    plant = SpindlePlant(p)
    start = plant.guide_position_mm
    pos, load = [], []
    for r in raw:
        pos.append(plant.guide_position_mm)
        load.append(plant.torque_nm / p.stall_torque_nm * 1000.0)
        plant.update(SpindleInputs(moving_speed_raw=int(r)), 1e-3)
    ticks = np.arange(0, raw.size, 20)
    out = sb.simulate_spindle_batch(np.tile(sb.theta_from_spindle_params(p), (3, 1)), raw, ticks,
                                    start_position_mm=start, params=p, play_start=0.0)
    assert np.ptp(out["guide_position_mm"], axis=0).max() == 0.0
    np.testing.assert_allclose(out["guide_position_mm"][0], np.array(pos)[ticks], atol=1e-9)
    np.testing.assert_allclose(out["load_permille"][0], np.array(load)[ticks], atol=1e-9)
    assert np.ptp(pos) > 1.0


def test_batched_spindle_refuses_bad_input():
    th = sb.theta_from_spindle_params(SpindleParams())
    with pytest.raises(ValueError, match="moving_speed_raw"):
        sb.simulate_spindle_batch(th, np.array([0, 5000]), np.array([0]), start_position_mm=0.0)
    with pytest.raises(ValueError, match="theta"):
        sb.simulate_spindle_batch(th[:3], np.array([0, 1]), np.array([0]), start_position_mm=0.0)


@pytest.fixture(scope="module")
def recs(tmp_path_factory):
    d = tmp_path_factory.mktemp("spindle")
    return {
        "clean": generate_spindle_recording(d / "clean.mcap", truth=None, seed=3, duration_s=10.0),
        "backlash": generate_spindle_recording(d / "backlash.mcap", truth={"backlash_mm": 0.8, "soft_fraction": 0.3},
                                               seed=3, duration_s=10.0, effect_id="screw_backlash"),
        "deadband": generate_spindle_recording(d / "deadband.mcap", seed=4, duration_s=10.0, effect_id="servo_deadband",
                                               truth={"deadband_in_raw": 70.0, "deadband_out_raw": 85.0}),
        "still": generate_spindle_recording(d / "still.mcap", truth={"backlash_mm": 0.8}, seed=5, duration_s=4.0,
                                            program=np.zeros(4000, dtype=np.int64)),
        "dir": d,
    }


def test_effect_free_spindle_recording_gives_none(recs):
    res = diagnose_spindle(recs["clean"].path, base=SpindleParams(), candidates=SPINDLE)
    assert res.status == "diagnosed" and res.verdict == "none" and res.effects == []
    truth = recs["clean"].params
    for name in ("no_load_speed_rpm", "friction_torque_nm"):  # the refit moves the class estimates to the unit's
        assert abs(res.nominal_refit[name]["fitted"] / getattr(truth, name) - 1.0) < 0.03


def test_servo_deadband_is_named_with_an_interval(recs):
    res = diagnose_spindle(recs["deadband"].path, base=SpindleParams(), candidates=SPINDLE)
    assert res.verdict == "missing_physics" and res.chosen == ["servo_deadband"]
    d = res.effects[0].params["deadband_raw"]
    assert 60.0 <= d["value"] <= 90.0  # truth: 70 moving in, 85 moving out (the library has one threshold)
    assert d["ci95"][0] <= d["value"] <= d["ci95"][1] and d["ci95"][1] - d["ci95"][0] < 100.0
    assert res.heldout_rms_after["spindle_load_permille"] < 0.8 * res.heldout_rms_before["spindle_load_permille"]


@pytest.mark.slow  # the drive half's refit runs too: about 20 s alone, 40 s on a loaded machine
def test_screw_backlash_found_through_the_api_and_loaded_by_the_sil(recs, tmp_path):
    res = diagnose(recs["backlash"].path, effects=["screw_backlash", "servo_deadband"])
    assert res.verdict == "missing_physics"
    assert [e.effect_id for e in res.effects] == ["screw_backlash"]
    b = res.effects[0].params["backlash_mm"]
    assert abs(b["value"] - 0.8 * (1 - 0.3 / 2)) < 0.15 * 0.68  # soft take-up: engaged after about b (1 - w/2)
    assert b["ci95"][0] < b["value"] < b["ci95"][1]
    assert res.first_line.startswith("left out: screw backlash backlash_mm")
    paths = write_report(res, tmp_path / "out")
    doc = json.loads(paths["report"].read_text())
    assert doc["spindle"]["verdict"] == "missing_physics" and doc["effects"][0]["id"] == "screw_backlash"
    model = load_model(paths["model"])
    assert model.spindle_params.screw_backlash_mm == pytest.approx(b["value"])
    from robowrangler_sim.sil import SilSession
    sil = SilSession(model=paths["model"], speedup=None)
    assert sil.spindle.params.screw_backlash_mm == pytest.approx(b["value"])


def test_no_spindle_motion_reports_the_spindle_effects_not_testable(recs, tmp_path):
    """Through the CLI: the spindle ids are accepted; a run whose spindle stands still (its truth has backlash)
    claims nothing and names both effects as not testable, with the reason."""
    import io

    from robowrangler.cli.environment import Environment
    from robowrangler.cli.main import main

    env = Environment(stdout=io.StringIO(), stderr=io.StringIO(), environ={})
    code = int(main(["diagnose", str(recs["still"].path), "--effects", "screw_backlash,servo_deadband",
                     "--out", str(tmp_path / "rep"), "--json"], env))
    assert code == 0, env.stderr.getvalue()
    doc = json.loads(env.stdout.getvalue())
    assert doc["verdict"] == "none" and doc["effects"] == []
    cov = doc["coverage"]
    assert {"screw_backlash", "servo_deadband"} <= set(cov["effects_not_testable"])
    assert "hardly moves" in cov["spindle_not_testable_reason"]
    assert doc["spindle"]["status"] == "not_testable" and doc["closed_loop"] is None


@pytest.mark.slow  # three SIL runs of about 10 s simulated each: about 45 s alone, 95 s on a loaded machine
def test_closed_loop_error_falls_with_the_fitted_model(tmp_path):
    """A closed-loop SIL recording (the real firmware core) of a spindle with a dead band: diagnosed, the written
    model loaded in the SIL, which replays the recording's commands closed loop: the guide's error falls."""
    from robowrangler_sim.diagnose.proof.spindle_sil_recording import record_spindle_sil

    path = record_spindle_sil(tmp_path / "sil.mcap", truth={"deadband_in_raw": 150.0, "deadband_out_raw": 150.0},
                              seed=2, moves_mm=(8.0, 14.0, 12.0, 12.5, 6.0, 7.0, 6.5), hold_s=0.9)
    res = diagnose(path, effects=["screw_backlash", "servo_deadband"], closed_loop=True)
    assert [e.effect_id for e in res.effects] == ["servo_deadband"]
    d = res.effects[0].params["deadband_raw"]
    assert d["ci95"][0] <= 150.0 <= d["ci95"][1]
    cl = res.report["closed_loop"]
    assert cl["replayed_commands"] >= 10 and cl["not_replayed"] == []
    guide = cl["rms"]["guide_position_m"]
    assert guide["fitted"] < 0.5 * guide["nominal"]
    paths = write_report(res, tmp_path / "out")
    assert "Closed loop" in paths["html"].read_text()
