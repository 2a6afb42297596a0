"""The identifiability oracle of the diagnose proof: can the effect be named from this recording at all?

The truth is put to the engine's own acceptance rule. The truth's candidate is the nominal model plus the effect
as the truth has it, in its true form and size: the truth plant (true base parameters) driven by the recording's
pulses as the engine reconstructs them, run with the effect and without it; the difference, observed as the
engine observes a model (DriveReplay.observe: the mean speed between the recorded encoder edge times, the volts
at the observation's tick), is added to the engine's nominal model, whose base parameters are refitted under it
(ModelFitter, started from the truth's values and from the nominal refit's) as every candidate's are. It is
scored against the diagnosis's refitted nominal model on the same observations, weights, fit samples and
held-out blocks (NominalBasis.score_prediction: select.score_model, select.accepted), counted with the
parameters a candidate for the effect has (the nominal refit's plus the library law's), though none of the
effect's own is fitted. If even the truth is not accepted, the effect is not identifiable from this recording by
the engine's rule, whatever the law, and the right answer is "none" (or "not_identifiable").

Left out of the truth's prediction: the effect's random part (a delay's jitter: no model predicts its
realisation), and the per-tick pulses the recording does not keep. The truth plant's own run (exact_prediction,
TruthCase.tick_truth) has them; its residual is the measurement noise and quantisation only (reported as
exact_rms: the check that the truth is the truth), but it beats the refitted nominal model even on effect-free
recordings, since the engine's batched plant and the pulse interpolated between 100 Hz records leave a misfit
above the noise there: judged with it, the oracle would call the engine's modelling error an effect.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robowrangler_sim.diagnose.candidates import LIBRARY
from robowrangler_sim.diagnose.fit import ModelFitter
from robowrangler_sim.diagnose.parameters import NOMINAL_REFIT
from robowrangler_sim.diagnose.proof.generator import TruthCase, run_truth
from robowrangler_sim.diagnose.residuals import CHANNELS, Residuals, channel_noise
from robowrangler_sim.plants import drive_batch as db

TICK_S = 1e-3


@dataclass(frozen=True)
class OracleVerdict:
    """identifiable: the truth's candidate is accepted over the refitted nominal model by the engine's rule.
    evidence: the rule's (select.accepted: delta_bic, truth - nominal refit BIC; heldout_lr, 2 ln of the truth's
    held-out likelihood ratio over the nominal refit; ...).
    n_params: what the truth was counted as. Residual RMS per channel on every observed sample: truth_rms (the
    truth's candidate), exact_rms (the truth plant's own run: the measurement noise and quantisation),
    nominal_rms (the refitted nominal model). noise: the engine's noise estimate per channel (median over
    observation kinds). heldout_rms_truth: the truth's candidate on the held-out blocks. effect_rms: RMS of what
    the effect adds to the observations (0: effect-free)."""

    identifiable: bool
    evidence: dict[str, float]
    n_params: int
    truth_rms: dict[str, float]
    exact_rms: dict[str, float]
    nominal_rms: dict[str, float]
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
                "oracle_noise": self.noise, "oracle_effect_rms": self.effect_rms}


def effect_param_count(effect_id: str | None) -> int:
    """Parameters a candidate for effect_id is counted with: the nominal refit's plus the library law's (an id the
    library has no law for: its key parameter, one)."""
    if effect_id is None:
        return len(NOMINAL_REFIT)
    law = LIBRARY.get(effect_id)
    return len(NOMINAL_REFIT) + (len(law().params) if law is not None else 1)


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


def effect_contribution(case: TruthCase, replay) -> dict[str, np.ndarray]:
    """What the truth effect adds to the recording's observations (channel -> (S,)): the truth plant (true base
    parameters, seed) driven by the recording's pulses as the engine reconstructs them (replay.data.pulse_us),
    with the effect in its true form minus without it. The effect's random part (a delay's jitter) is left out:
    no model can predict its realisation, so the truth's prediction is its systematic part. Zero for an
    effect-free case."""
    data = replay.data
    if case.effect is None:
        return {c: np.zeros(data.time_s.size) for c in CHANNELS}
    k0 = _first_tick(data)
    if k0 > data.preroll_ticks:
        raise ValueError(f"{case.path}: the first telemetry record is {k0} ticks after power-up, more than the "
                         f"replay's pre-roll ({data.preroll_ticks}): the truth's first ticks have no recorded pulse")
    pulse = data.pulse_us[data.preroll_ticks - k0:]  # from the truth plant's power-up
    with_effect = _observe_run(replay, run_truth(case.params, case.effect.systematic(), case.seed, pulse), k0)
    without = _observe_run(replay, run_truth(case.params, None, case.seed, pulse), k0)
    return {c: with_effect[c] - without[c] for c in CHANNELS}


class _WithEffect:
    """The engine's replay with a fixed contribution added to its channels: the nominal model plus the true
    effect, its base parameters free (ModelFitter fits through predict)."""

    def __init__(self, replay, added: dict[str, np.ndarray]) -> None:
        self.replay = replay
        self.data = replay.data
        self.added = added

    def predict(self, theta: np.ndarray, *, load_mask: np.ndarray | None = None) -> dict[str, np.ndarray]:
        out = self.replay.predict(theta, load_mask=load_mask)
        return {c: v + self.added[c][None, :] if c in self.added else v for c, v in out.items()}


def judge(case: TruthCase, result) -> OracleVerdict:
    """Is case's effect identifiable on its recording, by the engine's rule? result: diagnose(case.path)'s
    DiagnosisResult (its nominal_basis: the refitted nominal model, its weights, fit samples, held-out blocks)."""
    basis = result.nominal_basis
    if basis is None:
        raise ValueError(f"{case.path}: the diagnosis result carries no nominal_basis")
    replay = basis.replay
    exact = exact_prediction(case, replay)
    added = effect_contribution(case, replay)
    # the truth as the engine's candidate for it would be at best: the nominal model (its own base parameters
    # refitted, started from the truth's and from the nominal refit's, the better one) plus the true effect
    truth_theta = db.theta_from_params(case.params)
    cols = [s.column for s in NOMINAL_REFIT]
    starts = np.array([truth_theta[cols], basis.theta[cols]])
    model = _WithEffect(replay, added)
    fitter = ModelFitter(list(NOMINAL_REFIT), weights=basis.weights).fit(
        model, basis.theta, fit_mask=basis.fit_mask, starts=starts, start_columns=cols, bounds_ref=basis.theta_ref)
    n_params = effect_param_count(case.effect_id)
    sc, ok, ev, _ = basis.score_prediction(f"truth:{case.effect_id or 'none'}", fitter.prediction_, n_params)
    r_exact = Residuals().fit(basis.data, exact).residuals_
    r_truth = Residuals().fit(basis.data, fitter.prediction_).residuals_

    def rms(r: dict[str, np.ndarray]) -> dict[str, float]:
        return {c: float(np.sqrt(np.mean(r[c][basis.valid[c]] ** 2))) for c in CHANNELS}

    noise = {c: float(np.median(list(v.values()))) for c, v in channel_noise(basis.data).items() if v}
    return OracleVerdict(identifiable=ok, evidence=dict(ev), n_params=n_params,
                         truth_rms=rms(r_truth),
                         exact_rms=rms(r_exact), nominal_rms=rms(basis.residuals), noise=noise,
                         heldout_rms_truth=dict(sc.heldout_rms), effect_rms=rms(added))
