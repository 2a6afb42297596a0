"""The identifiability oracle of the diagnose proof: can the effect be named from this recording at all?

The truth is put to the engine's own acceptance rule (select.accepted: BIC on the fit samples and the held-out
test; select.reduces_own_channel: its channel's held-out error goes down), on the diagnosis's own observations, weights, fit samples and held-out blocks (NominalBasis), against the
nominal model refitted the engine's way (ModelFitter over NOMINAL_REFIT), counted with the parameters the
library's candidate for the effect has (though none of the effect's own is fitted). Both sides live in the truth
plant's world: the truth plant (true base parameters, seed) is run on the recording's pulses as the engine
reconstructs them, with the effect in its true form and size (a delay's jitter by its expectation: no model
predicts its draws) and without it, and the engine's batched plant is corrected by a fixed term so that at the
true parameters it equals the one run or the other; around that, the nominal parameters are refitted as every
candidate's are (started from the truth's values and from the engine's refit). The truth's candidate (corrected
to the run with the effect) must beat the nominal one (corrected to the run without it) by the rule. If it does
not, no law judged by that rule can name the effect from this recording, and "none" is the right answer.

Why both sides corrected: the batched plant and the per-tick truth plant differ by a little (the ESC frame
latch, the integration), and the pulse between 100 Hz records is interpolated. Added on one side only (the
effect's difference of two truth runs on top of the batched plant), that little decided small effects (a 1.6 ms
delay was "not identifiable" that the library's own law at the true value gets accepted); the truth plant's own
run (exact_prediction: the per-tick pulses, the jitter's draws) is at the measurement noise but beats the
engine's nominal refit on effect-free recordings too. So the comparison is made like with like, and the truth
plant's own run is reported only (exact_rms), as the check that the truth is the truth; an effect-free case has
nothing to add and is not identifiable by construction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robowrangler_sim.diagnose.candidates import LIBRARY
from robowrangler_sim.diagnose.fit import ModelFitter
from robowrangler_sim.diagnose.parameters import NOMINAL_REFIT
from robowrangler_sim.diagnose.proof.generator import TruthCase, run_truth
from robowrangler_sim.diagnose.residuals import CHANNELS, Residuals, channel_noise
from robowrangler_sim.diagnose.select import accepted, reduces_own_channel
from robowrangler_sim.plants import drive_batch as db

TICK_S = 1e-3


@dataclass(frozen=True)
class OracleVerdict:
    """identifiable: the truth's candidate is accepted over the refitted nominal model by the engine's rule.
    evidence: the rule's (select.accepted: delta_bic, truth - nominal refit BIC; heldout_lr, 2 ln of the truth's
    held-out likelihood ratio over the nominal refit; ...).
    n_params: what the truth was counted as. Residual RMS per channel on every observed sample: truth_rms (the
    truth's candidate), null_rms (the nominal model refitted in the truth plant's world, what it is judged
    against), exact_rms (the truth plant's own run: the measurement noise and quantisation), nominal_rms (the
    engine's refitted nominal model). noise: the engine's noise estimate per channel (median over
    observation kinds). heldout_rms_truth: the truth's candidate on the held-out blocks. effect_rms: RMS of what
    the effect adds to the observations (0: effect-free)."""

    identifiable: bool
    evidence: dict[str, float]
    n_params: int
    truth_rms: dict[str, float]
    exact_rms: dict[str, float]
    nominal_rms: dict[str, float]
    null_rms: dict[str, float]
    exact_speed_z: tuple[float, float] | None
    """The truth plant's own run's speed residual over the encoder's quantisation sigma (exact_z): its robust
    scale (about 1: the residual is quantisation) and the share beyond 4 (the first edges of a spin-up); None
    where not computed (the spindle)."""
    noise: dict[str, float]
    heldout_rms_truth: dict[str, float]
    effect_rms: dict[str, float]

    @property
    def delta_bic(self) -> float:
        return float(self.evidence["delta_bic"])

    @property
    def heldout_lr(self) -> float:
        return float(self.evidence.get("heldout_lr", float("nan")))

    def row(self) -> dict:
        """The bench row's fields."""
        return {"identifiable": self.identifiable, "oracle_evidence": dict(self.evidence),
                "oracle_delta_bic": self.delta_bic, "oracle_heldout_lr": self.heldout_lr,
                "oracle_truth_rms": self.truth_rms,
                "oracle_exact_rms": self.exact_rms, "oracle_nominal_rms": self.nominal_rms,
                "oracle_null_rms": self.null_rms, "oracle_exact_speed_z": self.exact_speed_z,
                "oracle_noise": self.noise, "oracle_effect_rms": self.effect_rms}


def param_count(effect_id: str | None, library: dict, refit: tuple) -> int:
    """Parameters a candidate for effect_id is counted with: the nominal refit's plus the library law's (an id the
    library has no law for: its key parameter, one; effect-free: the refit's)."""
    if effect_id is None:
        return len(refit)
    law = library.get(effect_id)
    return len(refit) + (len(law().params) if law is not None else 1)


def effect_param_count(effect_id: str | None) -> int:
    """Parameters a drive candidate for effect_id is counted with (param_count over LIBRARY and NOMINAL_REFIT)."""
    return param_count(effect_id, LIBRARY, NOMINAL_REFIT)


def _observe_run(replay, run: dict[str, np.ndarray], k0: int) -> dict[str, np.ndarray]:
    """A truth-plant run (per tick from its power-up, as run_truth / TruthCase.tick_truth) as the recording's
    observations (channel -> (S,)) through replay.observe; the replay grid's pre-roll is the plant at power-up."""
    data = replay.data
    n = data.pulse_us.size
    k = np.clip(np.arange(n) - data.preroll_ticks + k0, 0, run["rope_position_m"].size - 1)
    return replay.observe(np.abs(run["rope_position_m"])[k], run["battery_v"][k])


def _first_tick(data) -> int:
    """The generator tick of the recording's first telemetry record (the replay grid's time 0)."""
    return int(round(float(data.tel_time_s[0]) / TICK_S))


def exact_prediction(case: TruthCase, replay) -> dict[str, np.ndarray]:
    """The truth plant's own run (TruthCase.tick_truth: the per-tick pulses the recording does not keep, the
    effect's jitter as it fell) as the recording's observations: its residual is the measurement chain's noise
    and quantisation only."""
    if not case.tick_truth:
        raise ValueError(f"{case.path}: the TruthCase has no tick_truth (made by an older generator)")
    return _observe_run(replay, case.tick_truth, _first_tick(replay.data))


def quantisation_sigma_mps(data) -> np.ndarray:
    """(S,) the speed observation's own quantisation: the two edge times it spans, each floored to the 1 us edge
    clock (uniform errors: sigma 1 us / sqrt(6) on their difference, times speed / span), and, for a record that
    saw less than one edge, its floor (recording_data: the uniform spread of [0, one edge))."""
    span_s = np.maximum(data.edge_ticks[:, 1] - data.edge_ticks[:, 0], 1e-6) * TICK_S
    return np.hypot(np.abs(data.speed_mps) * 1e-6 / np.sqrt(6.0) / span_s, data.speed_floor_mps)


def exact_z(case: TruthCase, replay) -> np.ndarray:
    """The truth plant's own run's speed residual over quantisation_sigma_mps, on the observed samples: about unit
    scale where the truth is the truth (the residual is the encoder's quantisation)."""
    data = replay.data
    r = Residuals().fit(data, exact_prediction(case, replay)).residuals_["rope_speed_mps"]
    m = np.asarray(data.speed_valid, dtype=bool)
    return r[m] / np.maximum(quantisation_sigma_mps(data)[m], 1e-12)


def truth_runs(case: TruthCase, replay) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The truth plant (true base parameters, seed) driven by the recording's pulses as the engine reconstructs
    them (replay.data.pulse_us), with the effect in its true form and without it, as the recording's observations
    (channel -> (S,) each). The effect's random part (a delay's jitter) is left out: no model can predict its
    draws, so the truth's prediction is its systematic part. Effect-free: the same run twice."""
    data = replay.data
    k0 = _first_tick(data)
    if k0 > data.preroll_ticks:
        raise ValueError(f"{case.path}: the first telemetry record is {k0} ticks after power-up, more than the "
                         f"replay's pre-roll ({data.preroll_ticks}): the truth's first ticks have no recorded pulse")
    pulse = data.pulse_us[data.preroll_ticks - k0:]  # from the truth plant's power-up
    without = _observe_run(replay, run_truth(case.params, None, case.seed, pulse), k0)
    if case.effect is None:
        return without, without
    return _observe_run(replay, run_truth(case.params, case.effect.systematic(), case.seed, pulse), k0), without


class CorrectedReplay:
    """A replay (the drive's or the spindle's) with a fixed correction added to its predicted channels; everything
    else (data, what it measured) is the replay's own. The fitters fit through predict."""

    def __init__(self, replay, added: dict[str, np.ndarray]) -> None:
        self.replay = replay
        self.added = added

    def __getattr__(self, name: str):
        return getattr(self.replay, name)

    def predict(self, theta: np.ndarray, **kwargs) -> dict[str, np.ndarray]:
        out = self.replay.predict(theta, **kwargs)
        return {c: v + self.added[c][None, :] if c in self.added else v for c, v in out.items()}


def judge(case: TruthCase, result) -> OracleVerdict:
    """Is case's effect identifiable on its recording, by the engine's rule? result: diagnose(case.path)'s
    DiagnosisResult (its nominal_basis: the refitted nominal model, its weights, fit samples, held-out blocks)."""
    basis = result.nominal_basis
    if basis is None:
        raise ValueError(f"{case.path}: the diagnosis result carries no nominal_basis")
    replay = basis.replay
    with_effect, without = truth_runs(case, replay)
    truth_theta = db.theta_from_params(case.params)
    batch_truth = {c: v[0] for c, v in replay.predict(truth_theta[None, :]).items()}
    cols = [s.column for s in NOMINAL_REFIT]
    starts = np.array([truth_theta[cols], basis.theta[cols]])

    def refit(run: dict[str, np.ndarray]) -> ModelFitter:
        # the batched plant corrected to the truth plant's run at the true parameters (exact there), the nominal
        # parameters refitted around it as every candidate's are (started from the truth's and the refit's)
        fix = {c: run[c] - batch_truth[c] for c in CHANNELS}
        return ModelFitter(list(NOMINAL_REFIT), weights=basis.weights).fit(
            CorrectedReplay(replay, fix), basis.theta, fit_mask=basis.fit_mask, starts=starts, start_columns=cols,
            bounds_ref=basis.theta_ref)

    n_params = effect_param_count(case.effect_id)
    null = refit(without)
    sc_null, *_ = basis.score_prediction("nominal:truth_plant", null.prediction_, len(NOMINAL_REFIT))
    truth = null if case.effect is None else refit(with_effect)
    sc, _, _, r_truth = basis.score_prediction(f"truth:{case.effect_id or 'none'}", truth.prediction_, n_params)
    ok, ev = accepted(sc, sc_null)
    if case.effect_id in LIBRARY:  # and, as the engine asks of every law, it lowers its own channel's held-out error
        ok = ok and reduces_own_channel(LIBRARY[case.effect_id], sc, sc_null)
    r_exact = Residuals().fit(basis.data, exact_prediction(case, replay)).residuals_
    r_null = Residuals().fit(basis.data, null.prediction_).residuals_

    def rms(r: dict[str, np.ndarray]) -> dict[str, float]:
        return {c: float(np.sqrt(np.mean(r[c][basis.valid[c]] ** 2))) for c in CHANNELS}

    noise = {c: float(np.median(list(v.values()))) for c, v in channel_noise(basis.data).items() if v}
    z = exact_z(case, replay)
    return OracleVerdict(identifiable=ok, evidence=dict(ev), n_params=n_params, truth_rms=rms(r_truth),
                         exact_rms=rms(r_exact), nominal_rms=rms(basis.residuals), null_rms=rms(r_null),
                         exact_speed_z=(1.4826 * float(np.median(np.abs(z))), float(np.mean(np.abs(z) > 4.0))),
                         noise=noise, heldout_rms_truth=dict(sc.heldout_rms),
                         effect_rms=rms({c: with_effect[c] - without[c] for c in CHANNELS}))
