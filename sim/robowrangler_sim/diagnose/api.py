"""diagnose(recording) -> DiagnosisResult: the stages in order, as the issue lists them."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from robowrangler_sim.diagnose.candidates import LIBRARY, Candidate
from robowrangler_sim.diagnose.errors import ModelMismatchError, UnknownEffectError
from robowrangler_sim.diagnose.findings import EffectFinding, effect_finding, effect_params, nominal_refit_table
from robowrangler_sim.diagnose.fit import ModelFitter, jackknife_intervals
from robowrangler_sim.diagnose.gates import RegimeGate, tick_speed, uneven_split
from robowrangler_sim.diagnose.locate import Locator, spans_mask
from robowrangler_sim.diagnose.model_file import DiagnosedModel, load_model
from robowrangler_sim.diagnose.parameters import NOMINAL_REFIT
from robowrangler_sim.diagnose.recording_data import DriveData, load_drive_data
from robowrangler_sim.diagnose.regimes import coverage, dominant_regime, regime_labels
from robowrangler_sim.diagnose.replay import DriveReplay
from robowrangler_sim.diagnose.residuals import CHANNELS, Residuals, channel_noise, channel_weights, observed
from robowrangler_sim.diagnose.select import (ModelScore, accepted, effective_counts, equivalent, reduces_own_channel,
                                             score_model)
from robowrangler_sim.plants import DriveParams
from robowrangler_sim.plants import drive_batch as db

BLOCK_S = 0.5
HELDOUT_EVERY = 3  # every third block is held out of every fit
HELDOUT_GAP_S = (HELDOUT_EVERY - 1) * BLOCK_S
"""The longest stretch of fit samples between two held-out blocks: an effect confined to a shorter time window
can lie wholly in fit samples, where the held-out test never sees it act (Candidate.untested_reason)."""
ALPHA = 0.01
GATED_NFEV = 12  # solver steps of a law's fit confined to a speed range (it starts from the law's fit everywhere)


@dataclass
class _Fit:
    """One fitted model of the candidate stage: a candidate, everywhere or confined to a regime (gate)."""

    cand: Candidate
    params: tuple
    """The law's own ParamSpecs as fitted (confined: with the gated floors, Candidate.gated_params)."""
    fitter: ModelFitter
    score: ModelScore
    load_mask: np.ndarray | None
    gate: RegimeGate | None = None
    tick_gate: db.TickGate | None = None

    @property
    def effect_id(self) -> str:
        return self.cand.effect_id


@dataclass
class NominalBasis:
    """The refitted nominal model's score on one recording, with what scoring any other prediction of the same
    observations by the same rule needs (the weights, fit samples, held-out blocks and sample counts the
    candidates are judged with). The diagnose proof's identifiability oracle scores the truth plant with it."""

    data: DriveData = field(repr=False)
    replay: DriveReplay = field(repr=False)
    weights: dict[str, np.ndarray] = field(repr=False)
    fit_mask: np.ndarray = field(repr=False)
    block_id: np.ndarray = field(repr=False)
    heldout_blocks: np.ndarray = field(repr=False)
    n_eff: dict[str, float] = field(repr=False)
    valid: dict[str, np.ndarray] = field(repr=False)
    score: ModelScore = field(repr=False)
    residuals: dict[str, np.ndarray] = field(repr=False)
    theta: np.ndarray = field(repr=False)
    """The refitted nominal model's theta row (N_THETA,)."""
    theta_ref: np.ndarray = field(repr=False)
    """The model as given (the row the refit's relative bounds refer to)."""

    def score_prediction(self, name: str, prediction: dict[str, np.ndarray], n_params: int
                         ) -> tuple[ModelScore, bool, dict[str, float], dict[str, np.ndarray]]:
        """Score a prediction (channel -> (S,) on the recording's observations) as a candidate counted with
        n_params parameters is scored: (its ModelScore, accepted over the refitted nominal model, the evidence
        (select.accepted's: delta_bic, the held-out statistics), its residuals)."""
        r = _residuals(self.data, prediction)
        sc = score_model(name, n_params, r, self.weights, self.fit_mask, self.block_id, self.heldout_blocks,
                         self.n_eff, valid=self.valid)
        ok, ev = accepted(sc, self.score)
        return sc, ok, ev, r


@dataclass
class DiagnosisResult:
    """What diagnose found. ``report`` is the report.json document (see protocol/recording/diagnosis_report.md)."""

    recording: Path
    verdict: str
    effects: list[EffectFinding]
    not_identifiable: list[dict]
    nominal_refit: dict[str, dict]
    unexplained_fraction: float
    coverage: dict
    located: list[dict]
    candidates: list[dict]
    model: DiagnosedModel
    timings_s: dict[str, float]
    series: dict[str, np.ndarray] = field(repr=False, default_factory=dict)
    spindle: dict = field(default_factory=dict)
    """The spindle half's section of report.json (spindle_stage.SpindleDiagnosis.section)."""
    closed_loop: dict | None = None
    """Closed-loop before/after (closed_loop.py) when diagnose ran it: RMS per channel, model as given vs fitted."""
    nominal_basis: NominalBasis | None = field(repr=False, default=None)
    """The refitted nominal model's score and how to score another prediction against it (NominalBasis)."""
    noise_rms: dict[str, float] = field(default_factory=dict)
    """The recorded channels' own noise on the telemetry (residuals.channel_noise), what held-out errors compare to."""

    @property
    def first_line(self) -> str:
        from robowrangler_sim.diagnose.report import first_line
        return first_line(self)

    @property
    def report(self) -> dict:
        from robowrangler_sim.diagnose.report import report_json
        return report_json(self)


def _progress(stream, msg: str) -> None:
    if stream is not None:
        print(f"diagnose: {msg}", file=stream, flush=True)


def _residuals(data: DriveData, pred: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return Residuals().fit(data, pred).residuals_


def _resolve_effects(effects) -> list[Candidate]:
    if effects is None:
        return [cls() for cls in LIBRARY.values()]
    out = []
    for e in effects:
        if e not in LIBRARY:
            raise UnknownEffectError(f"effects: unknown effect id {e!r}; known: {', '.join(LIBRARY)}")
        out.append(LIBRARY[e]())
    return out


def diagnose(recording_path: str | Path, *, model: str | Path | DiagnosedModel | None = None,
             effects: list[str] | None = None, progress=None, pairs: bool = True,
             closed_loop: bool = False) -> DiagnosisResult:
    """Diagnose the drive channels of one recording against the model (None: the nominal DriveParams).

    effects: candidate ids to try (None: the whole library). progress: a text stream for progress lines.
    closed_loop: also run the SIL firmware on the recording's /host/command records with the model as given and
    with the fitted one (closed_loop.py) and report both closed-loop errors.
    Raises DiagnoseError subclasses for recordings or models it cannot work on.
    """
    # the fits' linear algebra is small (tall, ~10 columns): one BLAS thread each is fastest, and the batched
    # plant uses the cores instead (one batch row per thread)
    with threadpool_limits(limits=1):
        return _diagnose(recording_path, model=model, effects=effects, progress=progress, pairs=pairs,
                         closed_loop=closed_loop)


def _diagnose(recording_path, *, model, effects, progress, pairs, closed_loop) -> DiagnosisResult:
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    cpu0 = time.process_time()
    from robowrangler_sim.diagnose.spindle_stage import diagnose_spindle, merge_spindle, spindle_candidates
    spindle_cands, effects = spindle_candidates(effects)
    candidates = _resolve_effects(effects)
    data = load_drive_data(recording_path)
    if model is None:
        base = DiagnosedModel.nominal()
    elif isinstance(model, DiagnosedModel):
        base = model
    else:
        base = load_model(model)
    base.check_fits(data)
    if base.gated_effects():
        raise ModelMismatchError(f"model: {', '.join(base.gated_effects())} act(s) in one regime only; a diagnosis "
                                 "replays a model with effects everywhere: diagnose against the model without it")
    replay = DriveReplay(data, base.drive_params)
    theta_base = base.theta()
    n = data.time_s.size
    t = data.t_rel_s
    block_id = (t // BLOCK_S).astype(int)
    n_blocks = int(block_id.max()) + 1
    heldout_blocks = np.arange(HELDOUT_EVERY - 1, n_blocks, HELDOUT_EVERY)
    if heldout_blocks.size < 3:
        heldout_blocks = np.arange(1, n_blocks, 2)
    fit_mask = ~np.isin(block_id, heldout_blocks)
    labels, tel_labels = _labels(data)
    timings["load_s"] = time.perf_counter() - t0
    _progress(progress, f"{data.path.name}: {data.tel_time_s.size} telemetry records at {data.telemetry_hz:.0f} Hz, "
              f"{data.bursts} burst(s), {data.duration_s:.1f} s; replaying the nominal model")

    # --- replay + residuals of the model as given
    t1 = time.perf_counter()
    pred0 = replay.predict(theta_base[None, :])
    noise = channel_noise(data)
    weights = channel_weights(data, None, noise)
    timings["replay_s"] = time.perf_counter() - t1

    # --- nominal refit (first with noise weights, then each channel weighted by its refit residual)
    t1 = time.perf_counter()
    _progress(progress, "refitting the nominal parameters")
    nominal = ModelFitter(list(NOMINAL_REFIT), weights=weights).fit(replay, theta_base, fit_mask=fit_mask)
    r_nom = _residuals(data, nominal.prediction_)
    weights = channel_weights(data, {c: r_nom[c] for c in CHANNELS}, noise, fit_mask=fit_mask)
    nominal = ModelFitter(list(NOMINAL_REFIT), weights=weights).fit(replay, nominal.theta_, fit_mask=fit_mask,
                                                                    bounds_ref=theta_base)
    r_nom = _residuals(data, nominal.prediction_)
    valid = observed(data)
    n_eff = effective_counts(r_nom, fit_mask, valid=valid)
    score_nom = score_model("nominal_refit", len(NOMINAL_REFIT), r_nom, weights, fit_mask, block_id, heldout_blocks,
                            n_eff, valid=valid)
    basis = NominalBasis(data, replay, weights, fit_mask, block_id, heldout_blocks, n_eff, valid, score_nom, r_nom,
                         nominal.theta_, theta_base)
    timings["nominal_refit_s"] = time.perf_counter() - t1

    # --- locate
    t1 = time.perf_counter()
    on_tel = data.tel & valid["rope_speed_mps"]
    loc = Locator().fit(data.time_s[on_tel], {c: r[on_tel] for c, r in r_nom.items()})
    # the spans an effect may use are located on the fit samples only (the held-out ones judge it later)
    fit_tel = fit_mask & on_tel
    loc_signed = Locator(signed=True, bridge_s=BLOCK_S).fit(data.time_s[fit_tel],
                                                            {"rope_speed_mps": r_nom["rope_speed_mps"][fit_tel]})
    below = [(s.t0_s, s.t1_s) for s in loc_signed.spans_ if s.sign < 0]
    located = [{"channel": s.channel, "span_s": [round(s.t0_s, 3), round(s.t1_s, 3)],
                "significance": round(s.significance, 2),
                "regime": dominant_regime(labels, spans_mask(data.time_s, [(s.t0_s, s.t1_s)]))}
               for s in loc.spans_]
    timings["locate_s"] = time.perf_counter() - t1

    # --- candidates
    t1 = time.perf_counter()
    fits: dict[str, _Fit] = {}
    not_ident: list[dict] = []
    untested: list[dict] = []
    cov = coverage(tel_labels)
    cand_rows: list[dict] = [{"id": "nominal_refit", "status": "base", "heldout_rms": score_nom.heldout_rms,
                              "fit_rms": score_nom.fit_rms}]

    def fit_law(fid: str, cand: Candidate, own: tuple, theta_c: np.ndarray, *, load_mask=None, gate=None,
                tick_gate=None, max_nfev: int = 25, row: dict | None = None) -> None:
        """Fit a law (own parameters and every nominal one free, from theta_c and the law's start grid), score it
        against the refit (one parameter more when confined to a range), keep it in fits and the candidate table."""
        cols, grid = cand.start_grid(theta_c)
        if tick_gate is not None:
            grid = cand.starts_in_gate(grid, tick_gate.mask_on)
        fitter = ModelFitter(list(NOMINAL_REFIT) + list(own), weights=weights, max_nfev=max_nfev,
                             project_starts=cand.project_starts).fit(
            replay, theta_c, fit_mask=fit_mask, load_mask=load_mask, gate=tick_gate, starts=grid,
            start_columns=cols, bounds_ref=theta_base)
        sc = score_model(fid, len(NOMINAL_REFIT) + len(own) + (gate is not None),
                         _residuals(data, fitter.prediction_), weights, fit_mask, block_id, heldout_blocks, n_eff,
                         valid=valid)
        ok, ev = accepted(sc, score_nom)
        ok = ok and reduces_own_channel(cand, sc, score_nom)
        untested = cand.untested_reason(_values(fitter), heldout_gap_s=HELDOUT_GAP_S)
        if untested:
            ok, row = False, {**(row or {}), "reason": untested}
        fits[fid] = _Fit(cand, own, fitter, sc, load_mask, gate, tick_gate)
        cand_rows.append({"id": fid, **(row or {}), "status": "accepted" if ok else "rejected", **ev,
                          "heldout_rms": sc.heldout_rms,
                          "params": {p.name: round(p.value, 6) for p in fitter.params_
                                     if p.name in {s.name for s in own}}})

    for cand in candidates:
        ident = cand.identifiable(data)
        if not ident.identifiable:
            not_ident.append({"id": cand.effect_id, "reason": ident.reason,
                              "separating_measurement": ident.separating_measurement})
            cand_rows.append({"id": cand.effect_id, "status": "not_identifiable", "reason": ident.reason})
            continue
        visited = set(cov["visited"])
        if cand.needs_regimes and not visited.intersection(cand.needs_regimes):
            untested.append({"id": cand.effect_id, "needs_one_of": list(cand.needs_regimes)})
            cand_rows.append({"id": cand.effect_id, "status": "not_tested",
                              "reason": f"the recording never visits {' or '.join(cand.needs_regimes)}"})
            continue
        load_mask = None
        if cand.uses_located_spans:
            if not below:
                cand_rows.append({"id": cand.effect_id, "status": "no_span",
                                  "reason": "no span where the rope runs significantly slower than the model"})
                continue
            load_mask = _tick_mask(data, below)
        _progress(progress, f"fitting {cand.effect_id}")
        # the candidate's own parameters and every nominal one, from the refit: what the refit absorbed of the
        # effect (a dead band taken for Coulomb friction and inertia, a drag law for the resistance) is undone
        fit_law(cand.effect_id, cand, cand.params, cand.apply_neutral(nominal.theta_), load_mask=load_mask)
    # the same laws confined to either side of the speed that splits the refit's residual most unevenly
    gates = _gates_to_try(data, r_nom, nominal.prediction_["rope_speed_mps"], weights, fit_tel)
    unit_top = {s.column: s.bounds(theta_base[s.column])[1] for s in NOMINAL_REFIT}
    for g, tick_on in gates:
        for f in [f for f in list(fits.values()) if f.cand.gateable and f.gate is None]:
            cand = f.cand
            _progress(progress, f"fitting {cand.effect_id} {g.description}")
            # from the law's fit everywhere (the nominal parameters there already undo what the refit absorbed of
            # the effect), with every nominal parameter free as there; its start grid too, fewer solver steps
            fit_law(f"{cand.effect_id}@{g.key}", cand, cand.gated_params(nominal.theta_, unit_top),
                    f.fitter.theta_, gate=g, max_nfev=GATED_NFEV,
                    tick_gate=db.TickGate(tick_on, tuple(s.column for s in cand.params), nominal.theta_),
                    row={"effect": cand.effect_id, "gate": g.description})
    timings["candidates_s"] = time.perf_counter() - t1

    # --- select
    t1 = time.perf_counter()
    ok_ids = [row["id"] for row in cand_rows if row["status"] == "accepted"]
    ok_ids.sort(key=lambda i: fits[i].score.block_sse.sum())
    verdict = "none"
    chosen: list[str] = []
    chosen_fit: ModelFitter = nominal
    chosen_score = score_nom
    chosen_mask = None
    chosen_gate = None
    if ok_ids:
        best = ok_ids[0]
        # a law confined to a regime that does no better than the same law everywhere is that law everywhere
        plain = fits[best].effect_id
        if fits[best].gate is not None and plain in ok_ids and equivalent(fits[best].score, fits[plain].score):
            best = plain
        rivals = []
        for other in ok_ids:
            if fits[other].effect_id != fits[best].effect_id and fits[other].effect_id not in \
                    {fits[r].effect_id for r in rivals} and equivalent(fits[best].score, fits[other].score):
                rivals.append(other)
        chosen = [best]
        chosen_fit, chosen_score, chosen_mask = fits[best].fitter, fits[best].score, fits[best].load_mask
        chosen_gate = fits[best].tick_gate
        if rivals:
            verdict = "not_identifiable"
            names = [fits[i].effect_id for i in [best] + rivals]
            not_ident.insert(0, {"id": " / ".join(names), "reason": "these candidates explain the recording equally "
                                 "well on held-out spans", "separating_measurement":
                                 "; ".join(f"{fits[i].effect_id}: {fits[i].cand.separating_measurement}"
                                           for i in [best] + rivals), "candidates": names})
        else:
            verdict = "missing_physics"
            others = [i for i in ok_ids if fits[i].effect_id != fits[best].effect_id and fits[i].gate is None]
            if pairs and others and fits[best].gate is None:
                second = others[0]
                cand2 = fits[second].cand
                if not (cand2.uses_located_spans and fits[best].cand.uses_located_spans):
                    mask2 = fits[second].load_mask if fits[second].load_mask is not None else chosen_mask
                    theta_p = cand2.apply_neutral(chosen_fit.theta_)
                    _progress(progress, f"fitting {best} + {second}")
                    cols2, grid2 = cand2.start_grid(theta_p)
                    pair = ModelFitter(_look_alikes(fits[best].cand) + _look_alikes(cand2) + list(fits[best].cand.params)
                                       + list(cand2.params), weights=weights).fit(replay, theta_p, fit_mask=fit_mask, load_mask=mask2,
                                                            starts=grid2, start_columns=cols2,
                                                            bounds_ref=theta_base)
                    r_p = _residuals(data, pair.prediction_)
                    sp = score_model(f"{best}+{second}", len(pair.specs), r_p, weights, fit_mask, block_id,
                                     heldout_blocks, n_eff, valid=valid)
                    ok2, ev2 = accepted(sp, chosen_score)
                    ok2 = ok2 and reduces_own_channel(cand2, sp, chosen_score)
                    ok2 = ok2 and not any(c.untested_reason(_values(pair), heldout_gap_s=HELDOUT_GAP_S)
                                          for c in (fits[best].cand, cand2))
                    cand_rows.append({"id": f"{best}+{second}", "status": "accepted" if ok2 else "rejected", **ev2,
                                      "heldout_rms": sp.heldout_rms})
                    if ok2:
                        chosen = [best, second]
                        chosen_fit, chosen_score, chosen_mask = pair, sp, mask2
    timings["select_s"] = time.perf_counter() - t1

    # --- findings: the chosen model refitted with every parameter free (from its fit), intervals of the chosen
    # effects' parameters widened by a jackknife over the fit samples
    if verdict == "missing_physics":
        _progress(progress, "refitting the chosen model with every parameter free")
        chosen_specs = list(NOMINAL_REFIT) + [p for eid in chosen for p in fits[eid].params]
        final = ModelFitter(chosen_specs, weights=weights).fit(replay, chosen_fit.theta_, fit_mask=fit_mask,
                                                               load_mask=chosen_mask, gate=chosen_gate,
                                                               bounds_ref=theta_base)
        r_f = _residuals(data, final.prediction_)
        s_f = score_model("+".join(chosen), len(chosen_specs) + (chosen_gate is not None), r_f, weights, fit_mask,
                          block_id, heldout_blocks, n_eff, valid=valid)
        if s_f.block_sse.sum() <= chosen_score.block_sse.sum():
            chosen_fit, chosen_score = final, s_f
        _progress(progress, "intervals (jackknife)")
        jackknife_intervals(chosen_fit, {s.name for eid in chosen for s in fits[eid].cand.params}, student_t=True)
    r_after = _residuals(data, chosen_fit.prediction_)
    effects_out: list[EffectFinding] = []
    load_spans: list = [(a, b) for a, b in below] if "external_rope_load" in chosen else []
    if verdict == "missing_physics":
        for eid in chosen:
            cand = fits[eid].cand
            params = effect_params(chosen_fit, cand)
            spans = _improvement_spans(data, r_nom, r_after, weights, on_tel)
            if cand.uses_located_spans:
                spans = [[round(a, 3), round(b, 3)] for a, b in below]
            shift = data.tel_time_s[0] - data.preroll_ticks * 1e-3  # replay grid time -> recording time
            for name in getattr(cand, "time_params", ()):
                p = params[name]
                params[name] = {**p, "value": p["value"] + shift, "ci95": [c + shift for c in p["ci95"]]}
            if getattr(cand, "time_params", ()):
                spans = [[round(params["load_start_s"]["value"], 3), round(params["load_end_s"]["value"], 3)]]
                load_spans = spans
            effects_out.append(effect_finding(cand, params, spans_s=spans, labels=labels, time_s=data.time_s,
                                              rows=cand_rows, before=score_nom.heldout_rms,
                                              after=chosen_score.heldout_rms, row_id=eid, gate=fits[eid].gate))
    nominal_refit = nominal_refit_table(nominal, NOMINAL_REFIT, theta_base)
    sse_before = score_nom.block_sse.sum()
    unexplained = float(chosen_score.block_sse.sum() / sse_before) if sse_before > 0 else 0.0
    final_theta = chosen_fit.theta_
    model_out = base.extended(final_theta, effects=[fits[i].effect_id for i in chosen]
                              if verdict == "missing_physics" else [], load_spans_s=load_spans,
                              recording=str(data.path),
                              gates={fits[i].effect_id: (fits[i].gate, nominal.theta_) for i in chosen
                                     if verdict == "missing_physics" and fits[i].gate is not None})
    result = DiagnosisResult(
        recording=data.path, verdict=verdict, effects=effects_out, not_identifiable=not_ident,
        nominal_refit=nominal_refit, unexplained_fraction=unexplained,
        coverage={**cov, "effects_not_testable": [d["id"] for d in not_ident if "candidates" not in d],
                  "effects_not_tested": untested, "recording": {
                      "telemetry_hz": round(data.telemetry_hz, 1), "bursts": data.bursts,
                      "burst_s": round(data.burst_s, 3), "speed_source": data.speed_source,
                      "pulse_source": data.pulse_source, "missing": list(data.notes)}},
        located=located, candidates=cand_rows, model=model_out, timings_s=timings,
        series={"time_s": data.time_s, "speed_mps": np.where(valid["rope_speed_mps"], data.speed_mps, np.nan),
                "battery_v": data.battery_v,
                "pulse_us": data.pulse_us[data.sample_ticks.clip(max=data.pulse_us.size - 1)],
                "nominal_speed_mps": pred0["rope_speed_mps"][0], "refit_speed_mps": nominal.prediction_["rope_speed_mps"],
                "after_speed_mps": chosen_fit.prediction_["rope_speed_mps"],
                "nominal_battery_v": pred0["battery_v"][0], "refit_battery_v": nominal.prediction_["battery_v"],
                "after_battery_v": chosen_fit.prediction_["battery_v"],
                "heldout": ~fit_mask, "speed_band": labels["speed_band"], "motion": labels["motion"],
                "telemetry": data.tel.copy(), "speed_valid": valid["rope_speed_mps"].copy()},
        nominal_basis=basis,
        noise_rms={c: float(noise[c].get(int(data.kind[data.tel][0]), np.nan)) for c in ("rope_speed_mps", "battery_v")})
    _progress(progress, "spindle channels")
    merge_spindle(result, diagnose_spindle(data.path, base=base.spindle_params, candidates=spindle_cands,
                                           progress=progress))
    if closed_loop:
        from robowrangler_sim.diagnose.closed_loop import closed_loop_compare
        _progress(progress, "closed loop: the SIL firmware on the recording's commands, model as given and fitted")
        t1 = time.perf_counter()
        cmp = closed_loop_compare(data.path, nominal=base, fitted=result.model)
        result.series.update({f"closed_loop_{k}": v for k, v in cmp.pop("series").items()})
        result.closed_loop = cmp
        result.timings_s["closed_loop_s"] = time.perf_counter() - t1
    result.timings_s["total_s"] = time.perf_counter() - t0
    result.timings_s["cpu_s"] = time.process_time() - cpu0  # this process's CPU time (all its threads)
    return result


def _gates_to_try(data: DriveData, r_nom: dict[str, np.ndarray], v_nom: np.ndarray, weights: dict[str, np.ndarray],
                  fit_tel: np.ndarray) -> list[tuple[RegimeGate, np.ndarray]]:
    """Both sides of the speed split (gates.uneven_split) that divides the refit's weighted speed residual most
    unevenly on the fit samples where the rope or the refit (v_nom: its speed) moves, each with its mask on the
    replay's ticks."""
    v_tick = tick_speed(data)
    at = data.sample_ticks.clip(max=v_tick.size - 1)[fit_tel]
    w = np.broadcast_to(weights["rope_speed_mps"], r_nom["rope_speed_mps"].shape)[fit_tel]
    sides = uneven_split(v_tick[at], (r_nom["rope_speed_mps"][fit_tel] * w) ** 2, model_speed_mps=v_nom[fit_tel])
    return [] if sides is None else [(g, g.on(v_tick)) for g in sides]


def _look_alikes(cand: Candidate) -> list:
    """The nominal parameters a candidate trades against (its confused_with that are nominal parameters)."""
    return [s for s in NOMINAL_REFIT if s.name in cand.confused_with]


def _labels(data: DriveData) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Regime labels on the observation axis (from the nearest telemetry record) and on the telemetry."""
    tel = regime_labels(data.tel_time_s, data.tel_speed_mps)
    k = np.clip(np.searchsorted(data.tel_time_s, data.time_s), 0, data.tel_time_s.size - 1)
    return {kind: lab[k] for kind, lab in tel.items()}, tel


def _values(fitter: ModelFitter) -> dict[str, float]:
    return {p.name: p.value for p in fitter.params_}


def _tick_mask(data: DriveData, spans: list[tuple[float, float]]) -> np.ndarray:
    m = np.zeros(data.pulse_us.size)
    t_tick = data.tel_time_s[0] + (np.arange(data.pulse_us.size) - data.preroll_ticks) * 1e-3
    for a, b in spans:
        m[(t_tick >= a) & (t_tick <= b)] = 1.0
    return m


def _improvement_spans(data: DriveData, r_before, r_after, weights, on: np.ndarray) -> list[list[float]]:
    """Spans where the chosen model's improvement concentrates (windows of the telemetry observations with a
    significant drop in the weighted squared residual, as Locator flags them)."""
    gain = sum(((r_before[c] * weights[c]) ** 2).clip(max=9.0) - ((r_after[c] * weights[c]) ** 2).clip(max=9.0)
               for c in r_before)
    loc = Locator(signed=True, alpha=ALPHA).fit(data.time_s[on], {"gain": gain[on]})
    return [[round(s.t0_s, 3), round(s.t1_s, 3)] for s in loc.spans_ if s.sign > 0]
