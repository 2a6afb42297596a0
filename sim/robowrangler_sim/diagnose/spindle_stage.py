"""The spindle half of diagnose: replay the spindle commands, residuals on guide motion and load, locate, refit
the nominal spindle parameters, fit the spindle candidates (screw_backlash, servo_deadband), select.

The same rules as the drive (api.py): the nominal model's own parameters are refitted first within physical
bounds; a candidate is accepted only where it beats the refitted nominal model on held-out blocks (held-out
likelihood ratio) and on the fit samples (BIC), each by more than 10 (select.py); two accepted candidates that predict the
held-out blocks equally well are "not identifiable". A recording whose spindle never moves cannot test either
effect: it says so (status "not_testable") and claims nothing.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.findings import effect_finding, effect_params, nominal_refit_table
from robowrangler_sim.diagnose.locate import Locator, spans_mask
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.diagnose.regimes import dominant_regime
from robowrangler_sim.diagnose.residuals import noise_sigma
from robowrangler_sim.diagnose.select import HELDOUT_STRONG, accepted, effective_counts, equivalent, heldout_lr, score_model
from robowrangler_sim.diagnose.spindle_data import (SpindleData, load_spindle_data, spindle_coverage,
                                                    spindle_regimes)
from robowrangler_sim.diagnose.spindle_fit import SpindleFitter
from robowrangler_sim.diagnose.spindle_replay import CHANNELS, STEP_SAMPLES, SpindleReplay
from robowrangler_sim.plants import spindle_batch as sb
from robowrangler_sim.plants.spindle import SpindleParams

BLOCK_S = 0.5
HELDOUT_EVERY = 2
ALPHA = 0.01

SPINDLE_REFIT: tuple[ParamSpec, ...] = (
    ParamSpec("no_load_speed_rpm", sb.SP_NO_LOAD_RPM, "rpm", 0.85, 1.15, 59.0, relative=True),
    ParamSpec("response_time_s", sb.SP_RESPONSE_S, "s", 0.5, 2.5, 0.02, relative=True),
    ParamSpec("friction_torque_nm", sb.SP_FRICTION_NM, "N m", 0.5, 2.0, 0.05, relative=True),
)
"""The spindle's class estimates the refit may move (the stall torque only enters as friction / stall torque in
what a recording shows, so friction stands for both)."""

PARAM_FIELDS = {sb.SP_NO_LOAD_RPM: "no_load_speed_rpm", sb.SP_RESPONSE_S: "response_time_s",
                sb.SP_FRICTION_NM: "friction_torque_nm", sb.SP_DEADBAND_RAW: "servo_deadband_raw",
                sb.SP_HYST_RAW: "servo_deadband_hysteresis_raw", sb.SP_BACKLASH_MM: "screw_backlash_mm"}


@dataclass
class SpindleBasis:
    """The refitted nominal spindle model's score on one recording, with what scoring another prediction of the
    spindle channels by the same rule needs (api.NominalBasis's counterpart; the proof's oracle uses it)."""

    replay: SpindleReplay = field(repr=False)
    weights: dict[str, float] = field(repr=False)
    fit_mask: np.ndarray = field(repr=False)
    block_id: np.ndarray = field(repr=False)
    heldout_blocks: np.ndarray = field(repr=False)
    n_eff: dict[str, float] = field(repr=False)
    score: object = field(repr=False)
    residuals: dict[str, np.ndarray] = field(repr=False)
    theta: np.ndarray = field(repr=False)
    theta_ref: np.ndarray = field(repr=False)

    def score_prediction(self, name: str, prediction: dict[str, np.ndarray], n_params: int):
        """(ModelScore, accepted over the refitted nominal model, evidence, residuals) of a prediction (channel ->
        (S,) of the spindle CHANNELS), counted with n_params parameters."""
        r = _residuals(self.replay, prediction)
        sc = score_model(name, n_params, r, self.weights, self.fit_mask, self.block_id, self.heldout_blocks,
                         self.n_eff)
        ok, ev = accepted(sc, self.score)
        return sc, ok, ev, r


@dataclass
class SpindleDiagnosis:
    """What the spindle half found. status: "diagnosed" or "not_testable" (reason says why)."""

    status: str
    reason: str = ""
    verdict: str = "none"
    effects: list = field(default_factory=list)
    not_identifiable: list[dict] = field(default_factory=list)
    nominal_refit: dict[str, dict] = field(default_factory=dict)
    coverage: dict = field(default_factory=dict)
    located: list[dict] = field(default_factory=list)
    candidates: list[dict] = field(default_factory=list)
    untested: list[dict] = field(default_factory=list)
    params: SpindleParams | None = None
    chosen: list[str] = field(default_factory=list)
    heldout_rms_before: dict[str, float] = field(default_factory=dict)
    heldout_rms_after: dict[str, float] = field(default_factory=dict)
    unexplained_fraction: float = 1.0
    timings_s: dict[str, float] = field(default_factory=dict)
    series: dict[str, np.ndarray] = field(repr=False, default_factory=dict)
    nominal_basis: SpindleBasis | None = field(repr=False, default=None)

    def section(self) -> dict:
        """The report.json "spindle" section."""
        return {"status": self.status, "reason": self.reason, "verdict": self.verdict,
                "nominal_refit": self.nominal_refit, "coverage": self.coverage, "located": self.located,
                "candidates": self.candidates, "heldout_rms_before": self.heldout_rms_before,
                "heldout_rms_after": self.heldout_rms_after, "unexplained_fraction": self.unexplained_fraction}


def params_from_spindle_theta(base: SpindleParams, theta: np.ndarray, *, effects: list[str]) -> SpindleParams:
    """SpindleParams with the refitted class estimates and (only) the chosen effects' terms."""
    changes = {name: float(theta[col]) for col, name in PARAM_FIELDS.items()
               if col in (sb.SP_NO_LOAD_RPM, sb.SP_RESPONSE_S, sb.SP_FRICTION_NM)}
    changes["servo_deadband_raw"] = float(theta[sb.SP_DEADBAND_RAW]) if "servo_deadband" in effects else 0.0
    changes["servo_deadband_hysteresis_raw"] = float(theta[sb.SP_HYST_RAW]) if "servo_deadband" in effects else 0.0
    changes["screw_backlash_mm"] = float(theta[sb.SP_BACKLASH_MM]) if "screw_backlash" in effects else 0.0
    return dataclasses.replace(base, **changes)


def _progress(stream, msg: str) -> None:
    if stream is not None:
        print(f"diagnose: spindle: {msg}", file=stream, flush=True)


def _residuals(replay: SpindleReplay, pred: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {c: replay.measured[c] - (pred[c][0] if pred[c].ndim == 2 else pred[c]) for c in CHANNELS}


def not_testable(reason: str, candidates: list[Candidate], base: SpindleParams) -> SpindleDiagnosis:
    return SpindleDiagnosis(status="not_testable", reason=reason, verdict="none", params=base,
                            coverage=spindle_coverage(None),
                            candidates=[{"id": c.effect_id, "status": "not_testable", "reason": reason}
                                        for c in candidates])


def diagnose_spindle(recording: str | Path, *, base: SpindleParams, candidates: list[Candidate],
                     progress=None) -> SpindleDiagnosis:
    t0 = time.perf_counter()
    data, why = load_spindle_data(recording)
    if data is None:
        return not_testable(why, candidates, base)
    return diagnose_spindle_data(data, base=base, candidates=candidates, progress=progress, t0=t0)


def diagnose_spindle_data(data: SpindleData, *, base: SpindleParams, candidates: list[Candidate], progress=None,
                          t0: float | None = None) -> SpindleDiagnosis:
    t0 = time.perf_counter() if t0 is None else t0
    timings: dict[str, float] = {}
    replay = SpindleReplay(data, base)
    theta_base = replay.theta0
    t = data.t_rel_s
    block_id = (t // BLOCK_S).astype(int)
    n_blocks = int(block_id.max()) + 1
    heldout_blocks = np.arange(HELDOUT_EVERY - 1, n_blocks, HELDOUT_EVERY)
    if heldout_blocks.size < 3:
        heldout_blocks = np.arange(1, n_blocks, 2)
    fit_mask = ~np.isin(block_id, heldout_blocks)
    fit_mask[:STEP_SAMPLES] = False
    labels = spindle_regimes(data)
    cov = spindle_coverage(labels)
    _progress(progress, f"{data.path.name}: {t.size} samples; replaying the nominal spindle")

    pred0 = replay.predict(theta_base[None, :])
    noise = {"guide_step_mm": noise_sigma(data.guide_mm) * np.sqrt(2.0),
             "spindle_load_permille": noise_sigma(data.load_permille)}
    weights = {c: 1.0 / max(noise[c], 1e-9) for c in CHANNELS}
    # nominal refit: first with the data's noise weights, then each channel weighted by its refit residual
    _progress(progress, "refitting the nominal spindle parameters")
    nominal = SpindleFitter(list(SPINDLE_REFIT), weights=weights).fit(replay, theta_base, fit_mask=fit_mask)
    r_nom = _residuals(replay, nominal.prediction_)
    weights = {c: 1.0 / max(1.4826 * float(np.median(np.abs(r_nom[c][fit_mask]))), noise[c], 1e-9)
               for c in CHANNELS}
    nominal = SpindleFitter(list(SPINDLE_REFIT), weights=weights).fit(replay, nominal.theta_, fit_mask=fit_mask,
                                                                      bounds_ref=theta_base)
    r_nom = _residuals(replay, nominal.prediction_)
    n_eff = effective_counts(r_nom, fit_mask)
    score_nom = score_model("nominal_refit", len(SPINDLE_REFIT), r_nom, weights, fit_mask, block_id,
                            heldout_blocks, n_eff)
    basis = SpindleBasis(replay, weights, fit_mask, block_id, heldout_blocks, n_eff, score_nom, r_nom,
                         nominal.theta_, theta_base)
    timings["spindle_refit_s"] = time.perf_counter() - t0

    loc = Locator().fit(data.time_s, r_nom)
    located = [{"channel": s.channel, "span_s": [round(s.t0_s, 3), round(s.t1_s, 3)],
                "significance": round(s.significance, 2),
                "regime": dominant_regime(labels, spans_mask(data.time_s, [(s.t0_s, s.t1_s)]))}
               for s in loc.spans_]

    fits: dict[str, tuple[Candidate, SpindleFitter, object]] = {}
    rows: list[dict] = [{"id": "nominal_refit", "status": "base", "heldout_rms": score_nom.heldout_rms,
                         "fit_rms": score_nom.fit_rms}]
    untested: list[dict] = []
    visited = set(cov["visited"])
    for cand in candidates:
        if cand.needs_regimes and not visited.intersection(cand.needs_regimes):
            untested.append({"id": cand.effect_id, "needs_one_of": list(cand.needs_regimes)})
            rows.append({"id": cand.effect_id, "status": "not_tested",
                         "reason": f"the recording never visits {' or '.join(cand.needs_regimes)}"})
            continue
        _progress(progress, f"fitting {cand.effect_id}")
        theta_c = cand.apply_neutral(nominal.theta_)
        cols, grid = cand.start_grid(theta_c)
        fitter = SpindleFitter(list(SPINDLE_REFIT) + list(cand.params), weights=weights).fit(
            replay, theta_c, fit_mask=fit_mask, starts=grid, start_columns=cols, bounds_ref=theta_base,
            scan={s.name for s in cand.params})
        r_c = _residuals(replay, fitter.prediction_)
        sc = score_model(cand.effect_id, len(SPINDLE_REFIT) + len(cand.params), r_c, weights, fit_mask, block_id,
                         heldout_blocks, n_eff)
        ok, ev = accepted(sc, score_nom)
        fits[cand.effect_id] = (cand, fitter, sc)
        rows.append({"id": cand.effect_id, "status": "accepted" if ok else "rejected", **ev,
                     "heldout_rms": sc.heldout_rms,
                     "params": {p.name: round(p.value, 6) for p in fitter.params_
                                if p.name in {s.name for s in cand.params}}})
    timings["spindle_candidates_s"] = time.perf_counter() - t0 - timings["spindle_refit_s"]

    ok_ids = sorted((r["id"] for r in rows if r["status"] == "accepted"), key=lambda i: fits[i][2].block_sse.sum())
    verdict = "none"
    chosen: list[str] = []
    chosen_fit, chosen_score = nominal, score_nom
    not_ident: list[dict] = []
    if ok_ids:
        best = ok_ids[0]
        chosen = [best]
        chosen_fit, chosen_score = fits[best][1], fits[best][2]
        rivals = [o for o in ok_ids[1:] if equivalent(fits[best][2], fits[o][2])]
        if rivals:
            # both effects together may be what the recording holds: try the pair before calling them look-alikes
            pair_ok = False
            if len(ok_ids) >= 2:
                pair_ok, pair_fit, pair_score = _fit_pair(fits, ok_ids[:2], replay, weights, fit_mask, block_id,
                                                          heldout_blocks, n_eff, theta_base, rows, progress)
                if pair_ok and heldout_lr(pair_score, chosen_score) > HELDOUT_STRONG:
                    chosen, chosen_fit, chosen_score = ok_ids[:2], pair_fit, pair_score
                    verdict = "missing_physics"
            if verdict != "missing_physics":
                verdict = "not_identifiable"
                names = [best] + rivals
                not_ident.append({"id": " / ".join(names), "reason": "these candidates explain the spindle channels "
                                  "equally well on held-out spans", "separating_measurement":
                                  "; ".join(f"{i}: {fits[i][0].separating_measurement}" for i in names),
                                  "candidates": names})
        else:
            verdict = "missing_physics"
            if len(ok_ids) >= 2:
                pair_ok, pair_fit, pair_score = _fit_pair(fits, ok_ids[:2], replay, weights, fit_mask, block_id,
                                                          heldout_blocks, n_eff, theta_base, rows, progress)
                if pair_ok and accepted(pair_score, chosen_score)[0]:
                    chosen, chosen_fit, chosen_score = ok_ids[:2], pair_fit, pair_score

    r_after = _residuals(replay, chosen_fit.prediction_)
    effects_out = []
    if verdict == "missing_physics":
        spans = _improvement_spans(data.time_s, r_nom, r_after, weights)
        effects_out = [effect_finding(fits[eid][0], effect_params(chosen_fit, fits[eid][0]), spans_s=spans,
                                      labels=labels, time_s=data.time_s, rows=rows, before=score_nom.heldout_rms,
                                      after=chosen_score.heldout_rms) for eid in chosen]
    nominal_refit = nominal_refit_table(nominal, SPINDLE_REFIT, theta_base)
    sse_before = score_nom.block_sse.sum()
    timings["spindle_total_s"] = time.perf_counter() - t0
    return SpindleDiagnosis(
        status="diagnosed", verdict=verdict, effects=effects_out, not_identifiable=not_ident,
        nominal_refit=nominal_refit, coverage=cov, located=located, candidates=rows, untested=untested,
        params=params_from_spindle_theta(base, chosen_fit.theta_, effects=chosen if verdict == "missing_physics"
                                         else []),
        chosen=chosen if verdict == "missing_physics" else [], heldout_rms_before=score_nom.heldout_rms,
        heldout_rms_after=chosen_score.heldout_rms,
        unexplained_fraction=float(chosen_score.block_sse.sum() / sse_before) if sse_before > 0 else 0.0,
        timings_s=timings,
        series={"time_s": data.time_s, "guide_mm": data.guide_mm, "load_permille": data.load_permille,
                "nominal_guide_mm": pred0["guide_position_mm"][0],
                "refit_guide_mm": nominal.prediction_["guide_position_mm"],
                "after_guide_mm": chosen_fit.prediction_["guide_position_mm"],
                "nominal_load_permille": pred0["spindle_load_permille"][0],
                "refit_load_permille": nominal.prediction_["spindle_load_permille"],
                "after_load_permille": chosen_fit.prediction_["spindle_load_permille"], "heldout": ~fit_mask},
        nominal_basis=basis)


def _fit_pair(fits, ids, replay, weights, fit_mask, block_id, heldout_blocks, n_eff, theta_base, rows, progress):
    a, b = fits[ids[0]], fits[ids[1]]
    _progress(progress, f"fitting {ids[0]} + {ids[1]}")
    theta_p = b[0].apply_neutral(a[1].theta_)
    for s in b[0].params:
        theta_p[s.column] = b[1].theta_[s.column]
    specs = list(SPINDLE_REFIT) + list(a[0].params) + list(b[0].params)
    pair = SpindleFitter(specs, weights=weights).fit(replay, theta_p, fit_mask=fit_mask, bounds_ref=theta_base,
                                                     scan={s.name for s in a[0].params + b[0].params})
    r_p = _residuals(replay, pair.prediction_)
    sp = score_model("+".join(ids), len(specs), r_p, weights, fit_mask, block_id, heldout_blocks, n_eff)
    ok, ev = accepted(sp, a[2])
    rows.append({"id": "+".join(ids), "status": "accepted" if ok else "rejected", **ev, "heldout_rms": sp.heldout_rms})
    return ok, pair, sp


def _improvement_spans(t_s, r_before, r_after, weights) -> list[list[float]]:
    gain = sum(((r_before[c] * weights[c]) ** 2).clip(max=9.0) - ((r_after[c] * weights[c]) ** 2).clip(max=9.0)
               for c in r_before)
    loc = Locator(signed=True, alpha=ALPHA).fit(t_s, {"gain": gain})
    return [[round(s.t0_s, 3), round(s.t1_s, 3)] for s in loc.spans_ if s.sign > 0]


def spindle_candidates(effects: list[str] | None) -> tuple[list[Candidate], list[str] | None]:
    """(the spindle candidates to try, the remaining drive effect ids) from diagnose's ``effects`` argument
    (None: every spindle candidate, and None for the drive: its whole library)."""
    from robowrangler_sim.diagnose.candidates import SPINDLE_LIBRARY
    if effects is None:
        return [cls() for cls in SPINDLE_LIBRARY.values()], None
    return ([SPINDLE_LIBRARY[e]() for e in effects if e in SPINDLE_LIBRARY],
            [e for e in effects if e not in SPINDLE_LIBRARY])


def merge_spindle(result, sp: SpindleDiagnosis) -> None:
    """Fold the spindle half into the drive's DiagnosisResult (in place): verdict (missing physics on either side
    wins, then not identifiable, then none), effects, look-alikes, coverage (regimes visited, the spindle effects
    it could not test and why), candidate rows (marked plant "spindle"), the model (refitted spindle parameters
    and the chosen terms), the report's "spindle" section, timings, series."""
    if sp.verdict == "missing_physics":
        if result.verdict != "missing_physics":
            result.effects = []
        result.effects.extend(sp.effects)
        result.verdict = "missing_physics"
    elif sp.verdict == "not_identifiable" and result.verdict == "none":
        result.verdict = "not_identifiable"
    if sp.not_identifiable:
        if result.verdict == "not_identifiable" and not any("candidates" in d for d in result.not_identifiable):
            result.not_identifiable[:0] = sp.not_identifiable
        else:
            result.not_identifiable.extend(sp.not_identifiable)
    cov = result.coverage
    cov["visited"] = list(cov.get("visited", [])) + sp.coverage.get("visited", [])
    cov["not_visited"] = list(cov.get("not_visited", [])) + sp.coverage.get("not_visited", [])
    if sp.status == "not_testable":
        cov.setdefault("effects_not_testable", [])
        cov["effects_not_testable"] = list(cov["effects_not_testable"]) + [c["id"] for c in sp.candidates]
        cov["spindle_not_testable_reason"] = sp.reason
    cov["effects_not_tested"] = list(cov.get("effects_not_tested", [])) + sp.untested
    result.candidates.extend({**row, "plant": "spindle"} for row in sp.candidates if row["id"] != "nominal_refit"
                             or sp.status == "diagnosed")
    for row in result.candidates:
        if row.get("id") == "nominal_refit" and "plant" not in row:
            row["plant"] = "drive"
            break
    if sp.params is not None:
        result.model.spindle_params = sp.params
    for eid in sp.chosen:
        p = sp.params
        result.model.effects[eid] = ({"backlash_mm": p.screw_backlash_mm} if eid == "screw_backlash" else
                                     {"deadband_raw": p.servo_deadband_raw,
                                      "hysteresis_raw": p.servo_deadband_hysteresis_raw})
    result.spindle = sp.section()
    result.timings_s.update(sp.timings_s)
    result.series.update({f"spindle_{k}": v for k, v in sp.series.items()})
