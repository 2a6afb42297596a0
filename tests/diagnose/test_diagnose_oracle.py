"""The proof's identifiability oracles (proof/oracle.py, proof/spindle_oracle.py) on short generated recordings: the
truth put to the engine's acceptance rule calls a plain strong effect identifiable, gives an effect-free
recording's truth no advantage, and its truth is the truth (its own run's residual is the measurement noise)."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.diagnose import diagnose
from robowrangler_sim.diagnose.candidates.esc_latency import EscLatency
from robowrangler_sim.diagnose.parameters import NOMINAL_REFIT
from robowrangler_sim.diagnose.proof.generator import generate_recording, run_truth
from robowrangler_sim.diagnose.proof.oracle import exact_prediction, judge
from robowrangler_sim.diagnose.proof.spindle_cases import SpindleProofCase
from robowrangler_sim.diagnose.proof.spindle_generator import MM_PER_POSITION_UNIT, run_spindle_truth
from robowrangler_sim.diagnose.proof.spindle_oracle import judge_spindle
from robowrangler_sim.diagnose.spindle_stage import diagnose_spindle
from robowrangler_sim.diagnose.proof.truth_effects import LatencyTruth
from robowrangler_sim.diagnose.select import BIC_STRONG, HELDOUT_STRONG
from robowrangler_sim.plants import DriveParams, DrivePlant
from robowrangler_sim.plants.spindle import SpindleParams

DURATION_S = 6.0
ADC_SIGMA_V = float(np.hypot(DriveParams().battery_adc_noise_v, DriveParams().battery_adc_lsb_v / np.sqrt(12.0)))


def _latency(delay_s: float) -> LatencyTruth:
    return LatencyTruth("esc_latency", {"delay_s": delay_s}, delay_s=delay_s, jitter_s=0.001)


@pytest.fixture(scope="module")
def judged(tmp_path_factory):
    d = tmp_path_factory.mktemp("oracle")
    out = {}
    for name, effect, seed in (("plain", _latency(0.010), 3), ("clean", None, 21), ("tiny", _latency(0.0015), 5)):
        case = generate_recording(d / f"{name}.mcap", effect=effect, seed=seed, duration_s=DURATION_S)
        res = diagnose(case.path, effects=[])  # the refitted nominal model is all the oracle needs
        out[name] = (case, res, judge(case, res))
    return out


def _at_noise_level(v) -> None:
    """The truth plant's own run leaves the measurement chain's noise only: the battery ADC's known sigma, and on
    the speed the encoder's quantisation (each sample's residual over its own 1 us edge-clock sigma: unit scale,
    beyond 4 only at a spin-up's first edges)."""
    assert v.exact_rms["battery_v"] == pytest.approx(ADC_SIGMA_V, rel=0.1)
    z_scale, z_far = v.exact_speed_z
    assert 0.7 < z_scale < 1.6 and z_far < 0.01


def test_plain_strong_effect_is_identifiable(judged):
    case, res, v = judged["plain"]
    assert v.identifiable
    assert v.delta_bic < -BIC_STRONG and v.heldout_lr > HELDOUT_STRONG
    assert v.n_params == len(NOMINAL_REFIT) + len(EscLatency().params)  # counted as the library's candidate is
    assert v.effect_rms["rope_speed_mps"] > 10 * v.noise["rope_speed_mps"]
    assert v.truth_rms["rope_speed_mps"] < 0.5 * v.null_rms["rope_speed_mps"]
    _at_noise_level(v)


def test_effect_free_truth_has_no_advantage(judged):
    case, res, v = judged["clean"]
    assert v.effect_rms == {"rope_speed_mps": 0.0, "battery_v": 0.0}
    # the truth plant's own run is at the noise and clearly below the engine's refitted nominal model (base
    # parameters 3-10 % off, the batched plant, the pulse known at 100 Hz between bursts) ...
    _at_noise_level(v)
    assert v.exact_rms["rope_speed_mps"] < 0.8 * v.nominal_rms["rope_speed_mps"]
    # ... yet with no effect to add the truth's candidate is the nominal one: nothing to accept, naming anything
    # here would be a false alarm
    assert not v.identifiable
    assert v.delta_bic == 0.0 and v.heldout_lr == 0.0
    assert v.truth_rms == v.null_rms


def test_tiny_effect_judged_with_the_truth_at_the_noise(judged):
    case, res, v = judged["tiny"]
    _at_noise_level(v)
    assert 0.0 < v.effect_rms["rope_speed_mps"]
    assert np.isfinite(v.delta_bic) and np.isfinite(v.heldout_lr)
    # the truth's candidate carries the effect its nominal counterpart lacks: it fits the recording no worse
    assert v.truth_rms["rope_speed_mps"] <= v.null_rms["rope_speed_mps"] * 1.02


def test_truth_replay_is_the_recorded_run(judged):
    """run_truth on the pulses the speed loop commanded reproduces the generator's run tick for tick (the
    oracle's truth plant is the one that made the recording)."""
    case, _, _ = judged["plain"]
    run = run_truth(case.params, case.effect, case.seed, case.tick_truth["esc_command_us"])
    for k in ("rope_position_m", "rope_speed_mps", "battery_v"):
        np.testing.assert_array_equal(run[k], case.tick_truth[k])


def test_observe_refuses_a_trajectory_of_the_wrong_length(judged):
    case, res, _ = judged["clean"]
    replay = res.nominal_basis.replay
    n = replay.data.pulse_us.size
    with pytest.raises(ValueError, match="per tick of the replay grid"):
        replay.observe(np.zeros(n - 1), np.zeros(n))
    assert exact_prediction(case, replay)["rope_speed_mps"].shape == replay.data.time_s.shape


def test_the_truths_delay_is_its_jitters_expectation():
    """The oracle's truth of a jittered delay averages the pulse over the delay's distribution (no model predicts
    the draws): weights sum to 1 with the mean at the true delay; a step comes through as a ramp centred there."""
    eff = _latency(0.0017).systematic()
    eff.reset(np.random.default_rng(0))
    w = eff._w
    assert w.sum() == pytest.approx(1.0, abs=1e-9)
    assert np.dot(np.arange(w.size), w) == pytest.approx(1.7, abs=0.1)  # ticks (1 ms)
    out = [eff.pulse(1000.0 if k < 10 else 1300.0, k * 1e-3, DrivePlant(DriveParams())) for k in range(20)]
    assert out[9] == pytest.approx(1000.0) and out[19] == pytest.approx(1300.0)
    assert 1000.0 < out[11] < 1300.0  # between the levels at the delay
    assert eff.averaged and not _latency(0.0017).averaged  # the recording itself draws the jitter


# --- the spindle's oracle (proof/spindle_oracle.py)

@pytest.fixture(scope="module")
def spindle_judged(tmp_path_factory):
    d = tmp_path_factory.mktemp("spindle_oracle")
    out = {}
    for case in (SpindleProofCase("screw_backlash/plain/1", 150, "screw_backlash", "plain", 6.0),
                 SpindleProofCase("none/-/201", 201, None, "-", 6.0)):
        truth = case.generate(d / f"{case.concealment}.mcap")
        res = diagnose_spindle(truth.path, base=SpindleParams(), candidates=[])
        out[case.effect_id] = (truth, judge_spindle(truth, res))
    return out


def _spindle_at_noise_level(truth, v) -> None:
    """The truth spindle's own run leaves the registers' noise only: the load's sigma (and its whole-per-mille
    step), the position's (in mm, on a difference of two samples)."""
    load_sigma = float(np.hypot(truth.params.load_noise_permille, 1.0 / np.sqrt(12.0)))
    step_sigma = np.sqrt(2.0) * truth.params.position_noise_units * MM_PER_POSITION_UNIT
    assert v.exact_rms["spindle_load_permille"] == pytest.approx(load_sigma, rel=0.1)
    assert v.exact_rms["guide_step_mm"] == pytest.approx(step_sigma, rel=0.1)


def test_spindle_plain_backlash_is_identifiable(spindle_judged):
    truth, v = spindle_judged["screw_backlash"]
    assert v.identifiable and v.delta_bic < -BIC_STRONG and v.heldout_lr > HELDOUT_STRONG
    assert v.truth_rms["spindle_load_permille"] < 0.8 * v.null_rms["spindle_load_permille"]
    _spindle_at_noise_level(truth, v)
    # the oracle's truth spindle is the one that made the recording
    run = run_spindle_truth(truth.params, truth.plant_truth, truth.seed, truth.program)
    for k in ("guide_position_mm", "load_permille"):
        np.testing.assert_array_equal(run[k], truth.sample_truth[k])


def test_spindle_effect_free_truth_has_no_advantage(spindle_judged):
    truth, v = spindle_judged[None]
    assert not v.identifiable and v.delta_bic == 0.0
    _spindle_at_noise_level(truth, v)
    # the spindle's batched plant is the per-tick one: the nominal refit is as close to the truth as the noise lets
    assert v.nominal_rms["spindle_load_permille"] < 1.1 * v.exact_rms["spindle_load_permille"]
