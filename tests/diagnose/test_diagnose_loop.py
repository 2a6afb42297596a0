"""wrangler diagnose on the rope loop: short recordings from the first-principles string shooter (the truth) with
one physical change each, diagnosed blind against the chain's loop (robowrangler_sim.diagnose.loop)."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

from robowrangler.recorder import RecordingWriter, read_recording
from robowrangler_sim.diagnose import DiagnoseError, MissingChannelsError, ModelMismatchError, NoUsableSpanError
from robowrangler_sim.diagnose.loop import ContourFrameError, diagnose_loop
from robowrangler_sim.diagnose.loop.api import WITHIN_NOISE_Z
from robowrangler_sim.diagnose.loop.model_file import LoopModel
from robowrangler_sim.diagnose.loop.proof import LoopScript, LoopTruth, generate_loop_recording
from robowrangler_sim.diagnose.loop.report import write_loop_report
from robowrangler_sim.diagnose.select import HELDOUT_STRONG

STEADY = LoopScript(4.0, ((0.0, 5.0),), ((0.0, 0.1),))
CF0 = 0.08478874859262518


@pytest.fixture(scope="module")
def recs(tmp_path_factory):
    d = tmp_path_factory.mktemp("loop")
    out = {}
    out["none"] = generate_loop_recording(d / "none.mcap", truth=LoopTruth(None), script=STEADY, seed=11)
    out["speed"] = generate_loop_recording(d / "speed.mcap", truth=LoopTruth("loop_speed_dependence"),
                                           script=LoopScript(4.0, ((0.0, 4.5),), ((0.0, 0.1),)), seed=12)
    # C_f raised at 4 m/s: the truth's loop flies as at 4.5 m/s (raised by 20-30 % at 5 m/s it flutters instead and
    # leaves the v^2 C_f similarity the law rests on: bench_diagnose_loop.py --only interp)
    out["cf"] = generate_loop_recording(d / "cf.mcap", truth=LoopTruth("axial_drag_coefficient", cf_factor=1.25),
                                        script=LoopScript(4.0, ((0.0, 4.0),), ((0.0, 0.1),)), seed=13)
    out["wave"] = generate_loop_recording(
        d / "wave.mcap", truth=LoopTruth("transient_wave_dynamics"), seed=14,
        script=LoopScript(4.5, ((0.0, 5.0),), ((0.0, 0.0), (1.2, 0.0), (1.7, 0.35), (3.0, 0.35), (3.5, -0.1))))
    out["wind"] = generate_loop_recording(d / "wind.mcap", truth=LoopTruth("uniform_wind", wind_mps=1.5),
                                          script=STEADY, seed=15)
    out["upper"] = generate_loop_recording(d / "upper.mcap", truth=LoopTruth(None), script=STEADY, seed=16,
                                           branch_bump_m=0.02, branch="upper_branch")
    return out


def test_effect_free_recording_gives_none_and_says_what_cannot_be_seen(recs):
    res = diagnose_loop(recs["none"].path)
    assert res.verdict == "none", res.first_line
    assert res.candidates[0]["heldout_rms_mm"] < 2.0 * res.noise_mm
    assert 1.0 < res.noise_mm < 3.5  # the camera's 2 mm, estimated from the data
    blind = {d["id"]: d for d in res.not_identifiable}
    assert "2-D" in blind["out_of_plane_stiffness"]["reason"]
    assert "camera" in blind["out_of_plane_stiffness"]["separating_measurement"]
    assert "gyroscopic_base_rotation" in blind


def test_a_law_that_passes_the_held_out_test_within_the_camera_noise_is_not_a_finding(tmp_path):
    # effect-free, the module tilting slowly by 0.05 rad: the refitted chain is at the camera noise held out, and a
    # wind of 9 mm/s still passed the held-out test (1.92 -> 1.91 mm against 1.89 mm of noise; a false alarm on the
    # seed-79749 bench case, this recording)
    phi = float(np.random.default_rng(79749).uniform(-0.15, 0.35))
    case = generate_loop_recording(tmp_path / "tilt.mcap", truth=LoopTruth(None), seed=79749,
                                   script=LoopScript(5.0, ((0.0, 5.0),), ((0.0, phi), (5.0, phi + 0.05))))
    res = diagnose_loop(case.path)
    assert res.verdict == "none", res.first_line
    assert res.first_line.startswith("loop: none beyond noise")
    base = res.candidates[0]
    assert base["heldout_excess_z"] < WITHIN_NOISE_Z
    rows = {r["id"]: r for r in res.candidates}
    # the wind still wins the held-out test against the chain; it is held back only because nothing is left to explain
    assert rows["uniform_wind"]["status"] == "within_noise"
    assert rows["uniform_wind"]["heldout_lr"] > 10.0
    assert res.report["heldout_excess_z"] == base["heldout_excess_z"]


def test_held_out_blocks_include_a_turn_when_the_recording_has_two():
    from robowrangler_sim.diagnose.loop.api import heldout_blocks

    block_f = np.repeat(np.arange(8), 30)  # 8 one-second blocks of 30 frames
    steady = np.zeros(block_f.size, dtype=bool)
    np.testing.assert_array_equal(heldout_blocks(block_f, steady), [2, 5])  # every third, as without turns
    turns = (block_f == 1) | (block_f == 4)  # the module turns in blocks 1 and 4 (the Fig. 6a fast recording)
    held = heldout_blocks(block_f, turns)
    assert 4 in held and 1 not in held  # fitted on the first turn, tested on the second
    assert set(held) - {4}  # and steady blocks held out too
    assert set(held).issubset(set(range(8))) and len(held) >= 2


def test_speed_dependence_is_named_between_the_table_speeds(recs):
    res = diagnose_loop(recs["speed"].path)
    assert res.verdict in ("missing_physics", "not_identifiable"), res.first_line
    named = [e.effect_id for e in res.effects] or res.not_identifiable[0]["candidates"]
    assert "loop_speed_dependence" in named
    assert any(c["kind"] == "speed_band" and c["label"] == "4-5 m/s" and c["flagged"] for c in res.located["cells"])


def test_skin_friction_is_recovered_with_an_interval(recs, tmp_path):
    res = diagnose_loop(recs["cf"].path)
    assert res.verdict == "missing_physics", res.first_line
    e = res.effects[0]
    assert e.effect_id == "axial_drag_coefficient"
    p = e.params["skin_friction_coeff"]
    assert abs(p["value"] - 1.25 * CF0) / (1.25 * CF0) < 0.15
    assert p["ci95"][0] < p["value"] < p["ci95"][1]
    assert e.heldout_rms_mm_after < 0.6 * e.heldout_rms_mm_before
    # the extended model: a file the chain plant loads (shape table with the effect baked in)
    paths = write_loop_report(res, tmp_path / "rep")
    doc = json.loads(paths["report"].read_text())
    assert doc["verdict"] == "missing_physics" and paths["html"].exists() and paths["error"].exists()
    model = LoopModel.load(paths["model"])
    assert model.effects["axial_drag_coefficient"]["skin_friction_coeff"] == pytest.approx(p["value"])
    table = model.shape_table()
    assert table.rope_speed_mps.size > 3  # dense speed grid
    base = LoopModel().shape_table()
    moved = np.abs(table.contour(5.7, rope_speed_mps=5.0) - base.contour(5.7, rope_speed_mps=5.0)).max()
    assert moved > 0.01
    from robowrangler_sim.chain.plant import ChainPlant, PlantInputs

    plant = ChainPlant(table=table, params=model.chain_params(), initial=PlantInputs(rope_speed_mps=5.0))
    plant.advance(PlantInputs(rope_speed_mps=5.0), duration_s=0.5)
    assert plant.outputs().lift == 1.0


def test_the_table_is_continued_in_speed_as_the_truth_flies_between_and_below_its_speeds(tmp_path):
    """The laws' speed dependence S_lin against the string shooter at speeds the table (4, 5, 8 m/s) does not hold:
    the loop's one speed parameter is its weight over its axial drag, (v* / v)^2, and the truth is nearly linear in
    it (interpolating in v instead was 8.6 mm off at 4.5 m/s and left a lower C_f at 4 m/s beyond the law's reach)."""
    from robowrangler_sim.diagnose.loop import shape_model as sm
    from robowrangler_sim.diagnose.loop.data import load_loop_data
    from robowrangler_sim.diagnose.loop.replay import LoopReplay

    base = LoopModel.nominal()
    for v, f, limit_mm in ((4.5, 1.0, 3.0), (4.0, 0.86, 6.0)):  # between the table's speeds; C_f 0.86: as at 3.7 m/s
        case = generate_loop_recording(tmp_path / f"steady_{v}_{f}.mcap", script=LoopScript(2.5, ((0.0, v),),
                                                                                          ((0.0, 0.1),)),
                                       truth=LoopTruth("axial_drag_coefficient", cf_factor=f), seed=7, noise_m=0.0)
        data = load_loop_data(case.path, takeoff_speed_mps=base.takeoff_speed_mps(),
                              loop_length_of_guide=base.loop_length_m)
        shape = base.shape_model()
        replay = LoopReplay(data, shape, np.array([base.loop_length_m(g) for g in data.guide_m]))
        theta = base.theta(shape)
        theta[sm.TH_SPEED_GAIN], theta[sm.TH_CF] = 1.0, f * CF0  # the laws at the truth's own values
        off = np.sum((data.points_m - replay.contours(theta[None])[0]) * replay.normals, axis=-1)
        assert np.sqrt(np.mean(off ** 2)) * 1e3 < limit_mm, (v, f)


def test_the_wind_law_follows_the_truth_and_differs_from_a_skin_friction_change(tmp_path):
    """A tail wind of 0.4 m/s at 5 m/s: the law (the wind's skin friction and normal drag on the running rope, the
    string's response about the table's shape) at the truth's wind is within 3 mm of the string shooter's loop (the
    law before, a tilt of gravity plus a speed shift, was 20 mm off, further than the nominal chain's 13 mm), and no
    C_f change mimics it: the wind loads the two branches unevenly."""
    from robowrangler_sim.diagnose.loop import shape_model as sm
    from robowrangler_sim.diagnose.loop.data import load_loop_data
    from robowrangler_sim.diagnose.loop.replay import LoopReplay

    base = LoopModel.nominal()
    case = generate_loop_recording(tmp_path / "wind04.mcap", truth=LoopTruth("uniform_wind", wind_mps=0.4), seed=7,
                                   script=LoopScript(2.5, ((0.0, 5.0),), ((0.0, 0.1),)), noise_m=0.0)
    data = load_loop_data(case.path, takeoff_speed_mps=base.takeoff_speed_mps(), loop_length_of_guide=base.loop_length_m)
    shape = base.shape_model()
    replay = LoopReplay(data, shape, np.array([base.loop_length_m(g) for g in data.guide_m]))
    theta0 = base.theta(shape)

    def rms_mm(column, values):
        rows = np.repeat(theta0[None], len(values), axis=0)
        rows[:, column] = values
        off = np.sum((data.points_m[None] - replay.contours(rows)) * replay.normals[None], axis=-1)
        return np.sqrt(np.mean(off ** 2, axis=(1, 2))) * 1e3

    nominal = rms_mm(sm.TH_WIND_MPS, [0.0])[0]
    assert rms_mm(sm.TH_WIND_MPS, [0.4])[0] < min(3.0, 0.3 * nominal)
    assert rms_mm(sm.TH_CF, CF0 * np.linspace(0.8, 1.1, 13)).min() > 2.0 * rms_mm(sm.TH_WIND_MPS, [0.4])[0]


def test_a_lower_skin_friction_at_the_lowest_table_speed_is_named_with_its_value(tmp_path):
    """C_f 18 % low at the table's 4 m/s: the loop flies as at 3.6 m/s, below the table; the law reaches it (the
    table continued in (v* / v)^2 beyond its end) and the fit finds C_f, not the edge of the law's range (the law
    before stopped at 0.6 C_f0 here, 27 % off). Below the table the continuation is still about 6 mm off at 3.6 m/s,
    which a small wind beside C_f may take (named as the pair's second effect)."""
    case = generate_loop_recording(tmp_path / "cf_low.mcap", truth=LoopTruth("axial_drag_coefficient", cf_factor=0.82),
                                   script=LoopScript(4.0, ((0.0, 4.0),), ((0.0, 0.1),)), seed=18)
    res = diagnose_loop(case.path)
    assert res.verdict == "missing_physics", res.first_line
    assert res.effects[0].effect_id == "axial_drag_coefficient", res.first_line
    cf = res.effects[0].params["skin_friction_coeff"]["value"]
    assert abs(cf - 0.82 * CF0) / (0.82 * CF0) < 0.05, cf
    assert res.effects[0].heldout_rms_mm_after < 0.2 * res.effects[0].heldout_rms_mm_before


def test_transient_wave_dynamics_is_named_on_fast_module_turns(recs):
    """The truth's turn travels from the exit and the tip settles last, faster than the chain's servos: the wave law
    (delay s / c, then its own settling time) must beat the normal-drag lag (every point at once, through the servos)
    on the held-out frames by the strong level, not by a tie (the law without the settling ended the transient when
    the change had travelled and came within 1 mm of the normal-drag lag there, which was then named on some turns)."""
    res = diagnose_loop(recs["wave"].path)
    assert res.verdict == "missing_physics", res.first_line
    assert res.effects[0].effect_id == "transient_wave_dynamics"
    assert 1.0 < res.effects[0].params["wave_speed_mps"]["value"] < 20.0
    rows = {r["id"]: r for r in res.candidates}
    wave, drag = rows["transient_wave_dynamics"], rows["normal_drag_coefficient"]
    assert wave["heldout_lr"] - drag["heldout_lr"] > HELDOUT_STRONG, (wave, drag)
    assert wave["heldout_rms_mm"] < 0.85 * drag["heldout_rms_mm"], (wave, drag)
    assert 0.03 < res.effects[0].params["settling_time_s"]["value"] < 0.25  # below the servos' 0.25-1 s
    motion = {c["label"]: c for c in res.located["cells"] if c["kind"] == "motion"}
    assert motion["transient"]["flagged"]


def test_uniform_wind_is_named(recs):
    res = diagnose_loop(recs["wind"].path)
    accepted = [c["id"] for c in res.candidates if c.get("status") == "accepted"]
    assert "uniform_wind" in accepted, res.first_line
    assert res.effects and res.effects[0].effect_id == "uniform_wind", res.first_line
    assert res.effects[0].params["wind_speed_mps"]["value"] > 0  # blowing out along the launch direction


def test_a_stiff_rope_is_named_tip_bending_stiffness_with_its_stiffness(tmp_path):
    # the string shooter's rope 20 times stiffer (B = 1e-5 N m^2), a steady hold at 4 m/s: the tip rounds, waves
    # stand on the compressed upper branch, the lower branch lifts (bench/bench_loop_stiff_rope.py)
    b_true = 20.0 * 5.0e-7
    case = generate_loop_recording(tmp_path / "stiff.mcap", truth=LoopTruth("tip_bending_stiffness",
                                                                            bending_factor=20.0),
                                   script=LoopScript(4.0, ((0.0, 4.0),), ((0.0, 0.0),)), seed=17)
    res = diagnose_loop(case.path)
    assert res.verdict == "missing_physics", res.first_line
    e = res.effects[0]
    assert e.effect_id == "tip_bending_stiffness", res.first_line
    assert e.heldout_rms_mm_after < 0.6 * e.heldout_rms_mm_before  # 18 -> 8.6 mm here
    b = e.params["bending_stiffness_n_m2"]["value"]
    assert 0.4 * b_true < b < 2.5 * b_true  # a stiffer rope than the table's (5e-7), of the right size
    assert e.params["bending_stiffness_n_m2"]["ci95"][0] < b < e.params["bending_stiffness_n_m2"]["ci95"][1]
    # the extended model carries B and bakes the bent loop into the chain's shape table
    model = LoopModel.load(write_loop_report(res, tmp_path / "rep")["model"])
    assert model.effects["tip_bending_stiffness"]["bending_stiffness_n_m2"] == pytest.approx(b)
    moved = np.abs(model.shape_table().contour(0.0, rope_speed_mps=4.0)
                   - LoopModel().shape_table().contour(0.0, rope_speed_mps=4.0)).max()
    assert moved > 0.005


def test_two_effects_are_named_together_when_one_does_not_suffice(tmp_path):
    """C_f lowered by 20 %, flown at the table's 4 and 5 m/s and between them (where the truth's continuous speed
    dependence shows too): neither law alone explains the contours; the two together do. (Lowered: raised by 20 %,
    the truth's loop flutters at 5 m/s and leaves the v^2 C_f similarity the law rests on, bench_diagnose_loop.py
    --only interp.)"""
    script = LoopScript(8.0, ((0.0, 4.0), (3.0, 4.0), (3.3, 4.5), (5.5, 4.5), (5.8, 5.0)), ((0.0, 0.05),))
    case = generate_loop_recording(tmp_path / "pair.mcap", truth=LoopTruth("axial_drag_coefficient", cf_factor=0.8),
                                   script=script, seed=17)
    res = diagnose_loop(case.path)
    assert res.verdict == "missing_physics", res.first_line
    assert {e.effect_id for e in res.effects} == {"axial_drag_coefficient", "loop_speed_dependence"}, res.first_line
    cf = next(e for e in res.effects if e.effect_id == "axial_drag_coefficient").params["skin_friction_coeff"]
    assert abs(cf["value"] - 0.8 * CF0) / (0.8 * CF0) < 0.15
    assert " together with " in res.first_line
    assert set(res.model.effects) == {"axial_drag_coefficient", "loop_speed_dependence"}
    pair = next(c for c in res.candidates if "+" in c["id"] and c["status"] == "accepted")
    assert abs(pair["sensitivity_cosine"]) <= 0.9


def test_an_effect_on_the_upper_branch_is_located_there(recs):
    res = diagnose_loop(recs["upper"].path)
    assert res.located["part"] == "upper_branch", res.located["cells"][:4]
    lower = next(c for c in res.located["cells"] if c["label"] == "lower_branch")
    upper = next(c for c in res.located["cells"] if c["label"] == "upper_branch")
    assert upper["significance"] > 3 * lower["significance"]


def test_effects_can_be_selected(recs):
    res = diagnose_loop(recs["cf"].path, effects=["uniform_wind"])
    assert [c["id"] for c in res.candidates] == ["nominal_refit", "uniform_wind"]
    with pytest.raises(DiagnoseError, match="unknown loop effect id 'esc_latency'"):
        diagnose_loop(recs["cf"].path, effects=["esc_latency"])


# --- bad input ------------------------------------------------------------------------------------------------------
def _rewrite(src, dst, change, *, validate=True):
    rec = read_recording(src)
    with RecordingWriter(dst, source="simulator", seed=0, time_base="simulation", validate=validate) as w:
        for r in rec.records["/loop/observation"]:
            data = change(dict(r.data))
            if data is not None:
                w.write("/loop/observation", data, log_time_ns=r.log_time_ns)
    return dst


def test_contours_in_another_frame_are_refused(recs, tmp_path):
    mm = _rewrite(recs["none"].path, tmp_path / "mm.mcap",
                  lambda d: {**d, "points_m": [[x * 1e3, z * 1e3] for x, z in d["points_m"]]})
    with pytest.raises(ContourFrameError, match="loop length"):
        diagnose_loop(mm)
    down = _rewrite(recs["none"].path, tmp_path / "down.mcap",
                    lambda d: {**d, "points_m": [[x, -z] for x, z in d["points_m"]]})
    with pytest.raises(ContourFrameError, match="z up"):
        diagnose_loop(down)
    moved = _rewrite(recs["none"].path, tmp_path / "moved.mcap",
                     lambda d: {**d, "points_m": [[x + 0.4, z + 1.0] for x, z in d["points_m"]]})
    with pytest.raises(ContourFrameError, match="exit point at"):
        diagnose_loop(moved)


def test_too_few_points_no_phi_and_a_wrong_loop_length_are_named(recs, tmp_path):
    few = _rewrite(recs["none"].path, tmp_path / "few.mcap", lambda d: {**d, "points_m": d["points_m"][::8]})
    with pytest.raises(NoUsableSpanError, match="points"):
        diagnose_loop(few)
    no_phi = _rewrite(recs["none"].path, tmp_path / "nophi.mcap",
                      lambda d: {k: v for k, v in d.items() if k != "phi_rad"}, validate=False)
    with pytest.raises(DiagnoseError, match="phi_rad"):
        diagnose_loop(no_phi)
    longer = _rewrite(recs["none"].path, tmp_path / "long.mcap",
                      lambda d: {**d, "points_m": [[1.25 * x, 1.25 * z] for x, z in d["points_m"]]})
    with pytest.raises(ModelMismatchError, match="loop is .* long"):
        diagnose_loop(longer)
    # a shorter loop is kept for a loop effect to explain (a head wind crumples the tip); a rope that is just shorter
    # is not explained by any, and is refused with what was tried
    shorter = _rewrite(recs["none"].path, tmp_path / "shorter.mcap",
                       lambda d: {**d, "points_m": [[0.8 * x, 0.8 * z] for x, z in d["points_m"]]})
    with pytest.raises(ModelMismatchError, match="loop is .* long.*another rope length.*the contour is steady"):
        diagnose_loop(shorter)
    short = _rewrite(recs["none"].path, tmp_path / "short.mcap", lambda d: d if d["time_s"] < 0.9 else None)
    with pytest.raises(NoUsableSpanError, match="airborne camera frames"):
        diagnose_loop(short)


def test_cli_diagnoses_the_loop_and_exits_nonzero_on_bad_contours(recs, tmp_path):
    from robowrangler.cli.environment import Environment
    from robowrangler.cli.main import main

    def run(*argv):
        env = Environment(stdout=io.StringIO(), stderr=io.StringIO(), environ={})
        return int(main(list(argv), env)), env.stdout.getvalue(), env.stderr.getvalue()

    code, out, _ = run("--json", "diagnose", str(recs["cf"].path), "--out", str(tmp_path / "o"),
                       "--effects", "axial_drag_coefficient,uniform_wind")
    assert code == 0
    doc = json.loads(out.strip().splitlines()[-1])
    assert doc["loop"]["verdict"] == "missing_physics"
    assert doc["loop"]["effects"][0]["id"] == "axial_drag_coefficient"
    assert (tmp_path / "o" / "loop_model.json").exists()
    bad = _rewrite(recs["none"].path, tmp_path / "mm.mcap",
                   lambda d: {**d, "points_m": [[x * 1e3, z * 1e3] for x, z in d["points_m"]]})
    code, _, err = run("diagnose", str(bad), "--out", str(tmp_path / "b"))
    assert code == 1 and "loop" in err and "metres" in err
    code, _, err = run("sil", "--model", str(tmp_path / "o" / "loop_model.json"), "--duration", "0.1")
    assert code == 2 and "--scenario" in err


def test_the_fast_form_follows_the_chain_plant():
    """The fast form (table contour + first-order lag) against the MuJoCo chain plant: at steady state the chain
    lays its links on the table within its own accuracy (the paper's Fig. 5a: a few cm on a 2 m loop, the free lower
    branch), and after a 20 deg step both settle to the same shape."""
    from robowrangler_sim.chain.default_table import load_default_shape_table
    from robowrangler_sim.chain.params import ChainParams
    from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
    from robowrangler_sim.diagnose.loop.shape_model import LoopShapeModel
    from robowrangler_sim.shape_table import resample_by_arc_length

    table, p = load_default_shape_table(), ChainParams()
    fast = LoopShapeModel(table, rope=p.rope, tau_s=p.kd_upper_nms_per_rad / p.kp_upper_nm_per_rad, n_points=21)
    plant = ChainPlant(table=table, params=p, initial=PlantInputs(rope_speed_mps=5.0))

    def fast_contour(phi):
        return fast.targets(fast.theta0()[None], phi_rad=np.array([phi]), phidot_rad_s=np.zeros(1),
                            speed_mps=np.array([5.0]), loop_length_m=np.array([p.home_loop_length_m]))[0, 0]

    def chain_contour():
        return resample_by_arc_length(plant.chain_points_loop_plane_m(), 21)

    plant.advance(PlantInputs(rope_speed_mps=5.0, base_quat_wxyz=pitch_quat_wxyz(0.0)), duration_s=3.0)
    steady = np.linalg.norm(chain_contour() - fast_contour(0.0), axis=1)
    assert steady.max() < 0.06
    plant.advance(PlantInputs(rope_speed_mps=5.0, base_quat_wxyz=pitch_quat_wxyz(math.radians(20))), duration_s=2.5)
    after = np.linalg.norm(chain_contour() - fast_contour(math.radians(20)), axis=1)
    assert after.max() < 0.06
    # and the step moved the loop by far more than that
    assert np.linalg.norm(fast_contour(math.radians(20)) - fast_contour(0.0), axis=1).max() > 0.15
