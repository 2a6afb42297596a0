"""The identifiability oracle for the spindle proof (proof/oracle.py's counterpart on the spindle channels).

As the drive's: the truth spindle (SpindleTruthPlant, true class parameters) is run on the recording's commands
with the effect and without it; the batched spindle plant, corrected by a fixed term to equal the one run or
the other at the true parameters, has its nominal parameters refitted around it (SpindleFitter, started from the
truth's values and from the engine's refit); the truth's candidate (with the effect) must beat the nominal one
(without) by the spindle half's rule (select.accepted) on its observations, weights, fit samples and held-out
blocks (SpindleBasis), counted with the parameters the library's candidate for the effect has. Not accepted: the
effect is not identifiable from this recording, and "none" is the right answer. The truth spindle's own run
before the registers' noise (SpindleTruthCase.sample_truth) is reported as exact_rms: the registers' noise, the
check that the truth is the truth.
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.candidates import SPINDLE_LIBRARY
from robowrangler_sim.diagnose.proof.oracle import CorrectedReplay, OracleVerdict, param_count
from robowrangler_sim.diagnose.proof.spindle_generator import (TELEMETRY_PERIOD_TICKS, SpindleTruthCase,
                                                               run_spindle_truth)
from robowrangler_sim.diagnose.residuals import noise_sigma
from robowrangler_sim.diagnose.select import accepted
from robowrangler_sim.diagnose.spindle_fit import SpindleFitter
from robowrangler_sim.diagnose.spindle_replay import CHANNELS, steps
from robowrangler_sim.diagnose.spindle_stage import SPINDLE_REFIT
from robowrangler_sim.plants import spindle_batch as sb

TICK_S = 1e-3


def spindle_param_count(effect_id: str | None) -> int:
    """The nominal spindle refit's parameters plus the library law's for effect_id (param_count)."""
    return param_count(effect_id, SPINDLE_LIBRARY, SPINDLE_REFIT)


def _at_samples(run: dict[str, np.ndarray], data) -> dict[str, np.ndarray]:
    """A truth run (per telemetry record from the generator's first) at the recording's spindle samples, in the
    compared channels' terms."""
    first = int(round(float(data.time_s[0]) / (TELEMETRY_PERIOD_TICKS * TICK_S)))
    idx = first + data.sample_ticks // TELEMETRY_PERIOD_TICKS
    if idx[-1] >= run["guide_position_mm"].size:
        raise ValueError(f"{data.path}: the truth run has {run['guide_position_mm'].size} records, the recording "
                         f"{idx[-1] + 1}")
    return {"guide_step_mm": steps(run["guide_position_mm"][idx]), "spindle_load_permille": run["load_permille"][idx]}


def judge_spindle(case: SpindleTruthCase, result) -> OracleVerdict:
    """Is case's spindle effect identifiable on its recording by the spindle half's rule? result: the
    SpindleDiagnosis of case.path (diagnose_spindle; its nominal_basis)."""
    basis = result.nominal_basis
    if basis is None:
        raise ValueError(f"{case.path}: the spindle diagnosis carries no nominal_basis ({result.status}: "
                         f"{result.reason})")
    if case.program is None or not case.sample_truth:
        raise ValueError(f"{case.path}: the SpindleTruthCase has no program/sample_truth (an older generator)")
    replay = basis.replay
    data = replay.data
    without = _at_samples(run_spindle_truth(case.params, None, case.seed, case.program), data)
    with_effect = (_at_samples(run_spindle_truth(case.params, case.plant_truth, case.seed, case.program), data)
                   if case.plant_truth else without)
    truth_theta = sb.theta_from_spindle_params(case.params)
    batch_truth = {c: v[0] for c, v in replay.predict(truth_theta[None, :]).items()}
    cols = [s.column for s in SPINDLE_REFIT]

    def refit(run: dict[str, np.ndarray]) -> SpindleFitter:
        fix = {c: run[c] - batch_truth[c] for c in CHANNELS}
        return SpindleFitter(list(SPINDLE_REFIT), weights=basis.weights).fit(
            CorrectedReplay(replay, fix), basis.theta, fit_mask=basis.fit_mask,
            starts=np.array([truth_theta[cols], basis.theta[cols]]), start_columns=cols, bounds_ref=basis.theta_ref)

    n_params = spindle_param_count(case.effect_id)
    null = refit(without)
    sc_null, _, _, r_null = basis.score_prediction("nominal:truth_plant", {c: null.prediction_[c] for c in CHANNELS},
                                                   len(SPINDLE_REFIT))
    truth = null if not case.plant_truth else refit(with_effect)
    sc, _, _, r_truth = basis.score_prediction(f"truth:{case.effect_id or 'none'}",
                                               {c: truth.prediction_[c] for c in CHANNELS}, n_params)
    ok, ev = accepted(sc, sc_null)
    _, _, _, r_exact = basis.score_prediction("exact", _at_samples(case.sample_truth, data), n_params)

    def rms(r: dict[str, np.ndarray]) -> dict[str, float]:
        return {c: float(np.sqrt(np.mean(r[c] ** 2))) for c in CHANNELS}

    noise = {"guide_step_mm": noise_sigma(data.guide_mm) * np.sqrt(2.0),
             "spindle_load_permille": noise_sigma(data.load_permille)}
    return OracleVerdict(identifiable=ok, evidence=dict(ev), n_params=n_params, truth_rms=rms(r_truth),
                         exact_rms=rms(r_exact), nominal_rms=rms(basis.residuals), null_rms=rms(r_null),
                         exact_speed_z=None, noise=noise, heldout_rms_truth=dict(sc.heldout_rms),
                         effect_rms=rms({c: with_effect[c] - without[c] for c in CHANNELS}))
