"""wrangler diagnose on short generated recordings: recovery, none, bad inputs, the model file in the SIL."""

from __future__ import annotations

import json

import numpy as np
import pytest

from robowrangler_sim.diagnose import (DiagnoseError, MissingChannelsError, ModelMismatchError, NoUsableSpanError,
                                       diagnose)
from robowrangler_sim.diagnose.model_file import DiagnosedModel, load_model
from robowrangler_sim.diagnose.proof.generator import generate_recording
from robowrangler_sim.diagnose.locate import iou_s
from robowrangler_sim.diagnose.proof.cases import KEY_PARAM, proof_cases
from robowrangler_sim.diagnose.proof.truth_effects import LatencyTruth
from robowrangler_sim.diagnose.recording_data import load_drive_data
from robowrangler_sim.diagnose.replay import DriveReplay
from robowrangler_sim.diagnose.report import write_report
from robowrangler_sim.plants import DriveParams, DrivePlant
from robowrangler_sim.plants import drive_batch as db


def test_batched_plant_matches_the_per_tick_plant():
    p = DriveParams()
    pulse = np.full(3000, 1000.0)
    pulse[400:1400], pulse[1400:2200], pulse[2200:] = 1300.0, 1150.0, 1005.0
    plant = DrivePlant(p, seed=0)
    speed, volts = [plant.rope_speed_mps], [plant.battery_v]
    for u in pulse:
        plant.step_us(esc_pulse_us=float(u), dt_us=1000)
        speed.append(plant.rope_speed_mps)
        volts.append(plant.battery_v)
    rows = np.tile(db.theta_from_params(p), (3, 1))
    out = db.simulate_drive_batch(rows, db.consts_from_params(p), pulse, np.arange(pulse.size + 1), latch="exact")
    assert max(np.ptp(out["rope_speed_mps"], axis=0)) == 0.0  # the batch rows are independent and equal
    np.testing.assert_allclose(out["rope_speed_mps"][0], speed, atol=1e-4)
    np.testing.assert_allclose(out["battery_v"][0], volts, atol=1e-4)
    assert max(speed) > 5.0


def test_a_gated_effect_acts_only_on_its_ticks():
    """TickGate: a 20 ms delay confined to the second half equals the ungated model up to the gate's edge, and
    the fully delayed one's response to the step inside the gate; a gate on every tick is no gate."""
    p = DriveParams()
    pulse = np.full(4000, 1000.0)
    pulse[300:1500], pulse[2500:] = 1300.0, 1200.0
    off = db.theta_from_params(p)
    on = off.copy()
    on[db.TH_LATENCY] = 0.020
    consts, ticks = db.consts_from_params(p), np.arange(pulse.size + 1)
    plain = db.simulate_drive_batch(np.stack([off, on]), consts, pulse, ticks)["rope_speed_mps"]
    half = np.arange(pulse.size) >= 2000
    gate = db.TickGate(half, (db.TH_LATENCY,), off)
    gated = db.simulate_drive_batch(on, consts, pulse, ticks, gate=gate)["rope_speed_mps"][0]
    np.testing.assert_array_equal(gated[:2001], plain[0, :2001])  # no delay before the gate
    assert np.max(np.abs(gated[2530:2600] - plain[0, 2530:2600])) > 0.05  # the step at 2.5 s arrives late
    np.testing.assert_allclose(gated[2530:2600], plain[1, 2530:2600], atol=0.02)
    everywhere = db.TickGate(np.ones(pulse.size, bool), (db.TH_LATENCY,), off)
    np.testing.assert_array_equal(db.simulate_drive_batch(on, consts, pulse, ticks, gate=everywhere)
                                  ["rope_speed_mps"][0], plain[1])
    with pytest.raises(ValueError, match="gate.mask_on"):
        db.simulate_drive_batch(on, consts, pulse, ticks, gate=db.TickGate(half[:10], (db.TH_LATENCY,), off))


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    d = tmp_path_factory.mktemp("diag")
    clean = generate_recording(d / "clean.mcap", effect=None, seed=11, duration_s=8.0)
    lat = generate_recording(d / "latency.mcap", seed=1, duration_s=8.0,
                             effect=LatencyTruth("esc_latency", {"delay_s": 0.010}, delay_s=0.010, jitter_s=0.001))
    return {"clean": clean, "latency": lat, "dir": d}


def test_excite_recording_gives_bursts_fine_pulse_and_encoder_speed(recordings):
    data = load_drive_data(recordings["latency"].path)
    assert data.speed_source == "encoder" and data.bursts == 4 and data.burst_s == pytest.approx(4.0)
    assert data.telemetry_hz == pytest.approx(100.0)
    assert "fine" in data.pulse_source and "interpolated" in data.pulse_source
    assert data.notes == []
    # the mean speed between edge times agrees with the telemetry's filtered speed in steady holds
    tel = data.tel & data.speed_valid
    steady = np.interp(data.time_s[tel], data.tel_time_s, data.tel_speed_mps)
    hold = (data.time_s[tel] > 1.2) & (data.time_s[tel] < 1.3)
    assert np.allclose(data.speed_mps[tel][hold], steady[hold], atol=0.05)
    # burst samples carry the 1 kHz pulse, telemetry at 1/3 us
    assert np.any(np.abs(data.pulse_us * 3 - np.round(data.pulse_us * 3)) < 1e-6)


def test_older_50_hz_recording_still_diagnosed_and_says_what_it_lacks(tmp_path):
    rec = tmp_path / "old.mcap"
    generate_recording(rec, effect=None, seed=12, duration_s=8.0, telemetry_hz=50.0, fine_pulse=False, bursts=False)
    res = diagnose(rec, effects=["esc_latency"])
    assert res.verdict in ("none", "missing_physics", "not_identifiable")
    have = res.report["coverage"]["recording"]
    assert have["bursts"] == 0 and have["telemetry_hz"] == pytest.approx(50.0)
    assert any("no 1 kHz bursts" in m for m in have["missing"])
    assert any("whole us" in m for m in have["missing"])


def test_effect_free_recording_gives_none(recordings):
    res = diagnose(recordings["clean"].path, effects=["esc_latency", "rope_drag_law"])
    assert res.verdict == "none"
    assert res.effects == []
    assert res.first_line.startswith("none beyond noise")
    ids = {d["id"] for d in res.not_identifiable}
    assert ids == set()  # only the requested effects are considered


def test_latency_is_named_with_an_interval_and_the_model_improves(recordings, tmp_path):
    res = diagnose(recordings["latency"].path, effects=["esc_latency", "rope_drag_law", "wheel_slip"])
    assert res.verdict == "missing_physics"
    assert [e.effect_id for e in res.effects] == ["esc_latency"]
    delay = res.effects[0].params["delay_s"]
    assert 0.005 < delay["value"] < 0.013
    assert delay["ci95"][0] <= delay["value"] <= delay["ci95"][1]
    e = res.effects[0]
    assert e.heldout_rms_after["rope_speed_mps"] < 0.6 * e.heldout_rms_before["rope_speed_mps"]
    assert any(d["id"] == "wheel_slip" and "rope" in d["separating_measurement"] for d in res.not_identifiable)
    paths = write_report(res, tmp_path / "out")
    doc = json.loads(paths["report"].read_text())
    assert doc["verdict"] == "missing_physics" and doc["effects"][0]["id"] == "esc_latency"
    for key in ("params", "channels", "spans_s", "regime", "heldout_rms_before", "heldout_rms_after", "evidence"):
        assert key in doc["effects"][0]
    assert set(doc["nominal_refit"]["esc_lag_s"]) >= {"nominal", "fitted"}
    assert 0.0 <= doc["unexplained_fraction"] < 1.0
    assert b"data:image/png;base64," in paths["html"].read_bytes()
    # the written model replays the recording better than the nominal model
    model = load_model(paths["model"])
    assert model.effects["esc_latency"]["delay_s"] == pytest.approx(delay["value"])
    data = load_drive_data(recordings["latency"].path)
    err = {}
    for name, m in (("nominal", DiagnosedModel.nominal()), ("fitted", model)):
        pred = DriveReplay(data, m.drive_params).predict(m.theta()[None, :])
        r = (data.speed_mps - pred["rope_speed_mps"][0])[data.speed_valid]
        err[name] = float(np.sqrt(np.mean(r ** 2)))
    assert err["fitted"] < 0.6 * err["nominal"]


RIVAL = {"esc_latency": "rope_drag_law", "rope_drag_law": "battery_sag", "esc_deadband": "low_speed_friction",
         "battery_sag": "external_rope_load", "low_speed_friction": "esc_deadband"}


def _dev_case(name: str):
    """A case of the proof's dev set (bench/bench_diagnose.py DEV_SEEDS; the held-out seeds are never used here)."""
    return next(c for c in proof_cases(seeds=[1], clean_seeds=[]) if c.name == name)


def _diagnose_dev_case(name: str, tmp_path, effects: list[str]):
    """Generate a dev case's recording with its truth effect and diagnose it against effects: (result, the truth's
    spans)."""
    case = _dev_case(name)
    truth, spans = case.truth_effect()
    rec = tmp_path / f"{name.replace('/', '_')}.mcap"
    generate_recording(rec, effect=truth, seed=case.seed, duration_s=case.duration_s)
    return diagnose(rec, effects=effects), spans


@pytest.mark.parametrize("effect_id", list(RIVAL))
def test_each_candidate_is_recovered_from_a_generated_recording(effect_id, tmp_path):
    res, _ = _diagnose_dev_case(f"{effect_id}/plain/1", tmp_path, [effect_id, RIVAL[effect_id]])
    assert res.verdict == "missing_physics", res.first_line
    assert res.effects[0].effect_id == effect_id
    e = res.effects[0]
    assert e.heldout_rms_after["rope_speed_mps"] < e.heldout_rms_before["rope_speed_mps"]
    key = KEY_PARAM[effect_id]
    assert e.params[key]["ci95"][0] <= e.params[key]["value"] <= e.params[key]["ci95"][1]


def test_a_load_on_one_stretch_is_located_there(tmp_path):
    # a load acting above 5 m/s within one stretch
    res, spans = _diagnose_dev_case("external_rope_load/one_regime/1", tmp_path, ["external_rope_load", "rope_drag_law"])
    assert res.verdict == "missing_physics", res.first_line
    found = res.effects[0]
    assert found.effect_id == "external_rope_load"
    assert iou_s([tuple(x) for x in found.spans_s], list(spans)) >= 0.5


def test_a_gated_load_acts_only_on_its_ticks():
    """An external load confined to a regime (TickGate on its force column) acts within its window only where the
    gate is on: equal to the unloaded model before the gate opens, slower than it after."""
    p = DriveParams()
    pulse = np.full(3000, 1000.0)
    pulse[500:] = 1300.0  # after the ESC's arming hold at the minimum pulse
    off = db.theta_from_params(p)
    on = off.copy()
    on[[db.TH_EXT_LOAD, db.TH_EXT_T0, db.TH_EXT_T1]] = 0.5, 1.0, 2.9
    consts, ticks = db.consts_from_params(p), np.arange(pulse.size + 1)
    free, loaded = db.simulate_drive_batch(np.stack([off, on]), consts, pulse, ticks)["rope_speed_mps"]
    late = np.arange(pulse.size) >= 1800
    gate = db.TickGate(late, (db.TH_EXT_LOAD,), off)
    gated = db.simulate_drive_batch(on, consts, pulse, ticks, gate=gate)["rope_speed_mps"][0]
    assert np.max(np.abs(loaded[1100:1800] - free[1100:1800])) > 0.05  # the load slows the rope in its window
    np.testing.assert_array_equal(gated[:1801], free[:1801])  # confined: not before the gate opens
    assert np.max(free[1900:2900] - gated[1900:2900]) > 0.05


def test_a_load_only_at_high_speed_is_found_confined(tmp_path):
    """A load that acts only above 5 m/s within its stretch, which the refit half absorbs into friction (a case of
    round 5's held-out seeds, looked at since): found as a load confined to the fast range, where it acts. Before the
    load could be confined and its start rows judged with the nominal parameters re-adjusted, this came back
    "none beyond noise" with a 33 mm/s held-out error against 2 mm/s of noise."""
    case = next(c for c in proof_cases(seeds=[37376], clean_seeds=[]) if c.name == "external_rope_load/one_regime/37376")
    truth, spans = case.truth_effect()
    rec = tmp_path / "load_fast.mcap"
    generate_recording(rec, effect=truth, seed=case.seed, duration_s=case.duration_s)
    res = diagnose(rec, effects=["external_rope_load", "rope_drag_law"])
    assert res.verdict == "missing_physics", res.first_line
    found = res.effects[0]
    assert found.effect_id == "external_rope_load"
    assert "m/s and above" in found.regime["acts"]
    assert iou_s([tuple(x) for x in found.spans_s], list(spans)) >= 0.5
    assert found.heldout_rms_after["rope_speed_mps"] < 0.5 * found.heldout_rms_before["rope_speed_mps"]


def test_a_load_window_shorter_than_the_gap_between_held_out_blocks_is_not_a_finding():
    # a window that can lie wholly in fit samples is never tested on held-out data (with the windows' edges refined
    # on a finer grid, 0-0.2 s "loads" fitted to transients of effect-free runs passed the held-out test that way)
    from robowrangler_sim.diagnose.api import HELDOUT_GAP_S
    from robowrangler_sim.diagnose.candidates.external_rope_load import ExternalRopeLoad

    load = ExternalRopeLoad()
    short = load.untested_reason({"load_start_s": 6.49, "load_end_s": 6.67}, heldout_gap_s=HELDOUT_GAP_S)
    assert short is not None and "held-out" in short
    assert load.untested_reason({"load_start_s": 3.0, "load_end_s": 3.0 + 1.5 * HELDOUT_GAP_S},
                                heldout_gap_s=HELDOUT_GAP_S) is None


def test_a_latency_only_at_high_speed_is_named_with_its_regime(tmp_path):
    # the ESC late only above 5 m/s: everywhere, the law fails
    res, _ = _diagnose_dev_case("esc_latency/one_regime/1", tmp_path, ["esc_latency", "rope_drag_law"])
    assert res.verdict == "missing_physics", res.first_line
    found = res.effects[0]
    assert found.effect_id == "esc_latency"
    assert "m/s and above" in found.regime["acts"]
    assert f"esc latency ({found.regime['acts']}) delay_s" in res.first_line
    assert found.heldout_rms_after["rope_speed_mps"] < 0.8 * found.heldout_rms_before["rope_speed_mps"]
    plain = next(c for c in res.candidates if c["id"] == "esc_latency")
    gated = next(c for c in res.candidates if c.get("effect") == "esc_latency" and c["status"] == "accepted")
    assert gated["delta_bic"] < plain["delta_bic"] - 10  # confined, the law explains much more than everywhere
    terms = res.model.effects["esc_latency"]
    assert terms["gate_speed_min_mps"] >= 2.0 and 0.004 < terms["delay_s"] < 0.03
    back = load_model(res.model.save(tmp_path / "model.json"))
    assert back.gated_effects()["esc_latency"].speed_min_mps == terms["gate_speed_min_mps"]
    with pytest.raises(ModelMismatchError, match="one regime"):
        diagnose(res.recording, model=back, effects=["esc_latency"])


def test_sil_applies_a_gated_effect_only_in_its_regime(tmp_path):
    from robowrangler_sim.sil import SilSession

    def first_1200(gate: dict) -> int:
        model = DiagnosedModel(DriveParams(), {"esc_latency": {"delay_s": 0.006, **gate}})
        sil = SilSession(model=model.save(tmp_path / "gated.json"), speedup=None)
        return [sil.actuator_filters[0](u) for u in [1000] * 3 + [1200] * 10].index(1200)
    assert first_1200({"gate_speed_min_mps": 5.0}) == 3  # the rope at rest: out of the regime, not delayed
    assert first_1200({"gate_speed_max_mps": 2.0}) == 3 + 6  # in the regime: six 1 ms ticks late
    bad = DiagnosedModel(DriveParams(), {"esc_latency": {"delay_s": 0.006, "gate_speed_min_mps": 5.0,
                                                         "gate_speed_max_mps": 2.0}})
    with pytest.raises(ModelMismatchError, match="gate_speed_min_mps"):
        load_model(bad.save(tmp_path / "bad.json"))


def test_sil_applies_a_gated_load_only_in_its_regime(tmp_path):
    from robowrangler_sim.sil import SilSession

    def load_at_rest(gate: dict) -> float:
        model = DiagnosedModel(DriveParams(), {"external_rope_load": {"external_load_n": 0.4, **gate}},
                               external_load_spans_s=[(0.0, 100.0)])
        sil = SilSession(model=load_model(model.save(tmp_path / "load.json")), speedup=None)
        sil.tick_hooks[-1](sil)
        return sil.loads.external_rope_load_n
    assert load_at_rest({"gate_speed_min_mps": 5.0}) == 0.0  # the rope at rest: out of the regime
    assert load_at_rest({"gate_speed_max_mps": 2.0}) == pytest.approx(0.4)
    assert load_at_rest({}) == pytest.approx(0.4)


def test_the_escs_own_input_delay_reaches_the_sil(tmp_path):
    """The refit's ESC input delay (no DriveParams field) is carried by the model file and applied by the SIL:
    alone, and outside the speed range of a confined latency."""
    from robowrangler_sim.sil import SilSession

    def first_1200(model: DiagnosedModel) -> int:
        sil = SilSession(model=load_model(model.save(tmp_path / "m.json")), speedup=None)
        assert sil.actuator_filters, "no actuator filter: the delay was dropped"
        return [sil.actuator_filters[0](u) for u in [1000] * 3 + [1200] * 10].index(1200)

    assert first_1200(DiagnosedModel(DriveParams(), esc_input_delay_s=0.002)) == 3 + 2
    confined = {"esc_latency": {"delay_s": 0.006, "gate_speed_min_mps": 5.0}}
    assert first_1200(DiagnosedModel(DriveParams(), confined, esc_input_delay_s=0.002)) == 3 + 2  # at rest: outside
    th = DiagnosedModel(DriveParams(), esc_input_delay_s=0.002).theta()
    assert th[db.TH_LATENCY] == 0.002  # a diagnosis against this model replays it too
    doc = DiagnosedModel(DriveParams()).to_json()
    doc["esc_input_delay_s"] = -0.001
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    with pytest.raises(ModelMismatchError, match="esc_input_delay_s"):
        load_model(tmp_path / "bad.json")


def test_sil_session_loads_the_model_file(recordings, tmp_path):
    from robowrangler_sim.sil import SilSession

    model = DiagnosedModel(DriveParams(esc_lag_s=0.004), {"esc_latency": {"delay_s": 0.006}})
    path = model.save(tmp_path / "model.json")
    sil = SilSession(model=path, speedup=None)
    assert sil.plant.params.esc_lag_s == 0.004
    delayed = [sil.actuator_filters[0](u) for u in [1000] * 3 + [1200] * 10]
    assert delayed.index(1200) == 3 + 6  # six 1 ms ticks late
    with pytest.raises(ValueError, match="model"):
        SilSession(model=path, drive_params=DriveParams())


def test_bad_inputs_are_refused(recordings, tmp_path):
    src = recordings["clean"].path.read_bytes()
    corrupt = tmp_path / "corrupt.mcap"
    corrupt.write_bytes(b"not an mcap file at all" * 10)
    with pytest.raises(DiagnoseError, match="not a readable recording"):
        diagnose(corrupt)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src[:3000])
    with pytest.raises((MissingChannelsError, NoUsableSpanError)):
        diagnose(cut)
    still = tmp_path / "still.mcap"
    generate_recording(still, effect=None, seed=3, duration_s=3.0, pulse_us=np.full(3000, 1000.0))
    with pytest.raises(NoUsableSpanError, match="moves"):
        diagnose(still)
    from robowrangler.recorder import RecordingWriter
    empty = tmp_path / "no_telemetry.mcap"
    with RecordingWriter(empty, source="simulator", time_base="simulation", clock_ns=lambda: 0) as w:
        w.write("/sim/plant_truth", {"time_s": 0.0, "rope_speed_mps": 1.0})
    with pytest.raises(MissingChannelsError, match="telemetry"):
        diagnose(empty)
    other = DiagnosedModel(DriveParams(wheel_radius_m=0.02))
    with pytest.raises(ModelMismatchError, match="wheel_radius_m"):
        diagnose(recordings["clean"].path, model=other)
    bad = tmp_path / "bad_model.json"
    bad.write_text(json.dumps({"format": "robowrangler.drive_model", "format_version": 1,
                               "drive_params": {"wheel_radius_mm": 15}}))
    with pytest.raises(ModelMismatchError, match="wheel_radius_mm"):
        load_model(bad)


def test_cli_verb_exit_statuses_and_json(recordings, tmp_path):
    import io

    from robowrangler.cli.environment import Environment
    from robowrangler.cli.main import main

    def run(*argv):
        env = Environment(stdout=io.StringIO(), stderr=io.StringIO(), environ={})
        return int(main(list(argv), env)), env.stdout.getvalue(), env.stderr.getvalue()

    code, out, err = run("diagnose", str(recordings["clean"].path), "--effects", "esc_latency,wheel_slip",
                         "--out", str(tmp_path / "rep"), "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["verdict"] == "none" and doc["effects"] == []
    assert (tmp_path / "rep" / "report.html").exists() and (tmp_path / "rep" / "model.json").exists()
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"garbage")
    code, out, err = run("diagnose", str(bad))
    assert code == 1 and "not a readable recording" in err and out == ""
    code, _, err = run("diagnose", str(recordings["clean"].path), "--effects", "no_such_effect")
    assert code == 2 and "no_such_effect" in err


def test_coverage_names_the_regimes_and_effects_a_slow_run_cannot_test(tmp_path):
    pulse = np.full(5000, 1000.0)
    pulse[400:1600], pulse[1600:2800], pulse[2800:4000] = 1060.0, 1120.0, 1090.0  # never above ~4 m/s
    rec = tmp_path / "slow.mcap"
    generate_recording(rec, effect=None, seed=5, duration_s=5.0, pulse_us=pulse)
    res = diagnose(rec, effects=["rope_drag_law"])
    assert res.verdict == "none"
    assert "speed_band:> 8 m/s" in res.coverage["not_visited"]
    assert [d["id"] for d in res.coverage["effects_not_tested"]] == ["rope_drag_law"]
    assert next(c for c in res.candidates if c["id"] == "rope_drag_law")["status"] == "not_tested"
