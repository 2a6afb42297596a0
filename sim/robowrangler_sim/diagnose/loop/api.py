"""diagnose_loop(recording) -> LoopDiagnosis: the engine's stages (diagnose/api.py) on the loop's contours.

replay (the chain's fast form driven by rope speed, guide and phi) -> residuals (signed normal distance, noise from
the data) -> locate (loop part, phi / speed band, steady / transient, time spans) -> refit the chain's own
parameters (servo time constant kd/kp, loop length scale) -> each loop candidate fitted with 95 % intervals
(diagnose.fit.ModelFitter) -> select on held-out frames and BIC (diagnose.select) -> when the best effect leaves the
contours above the camera noise, it and each next-best one fitted together, kept only if the pair beats the single
effect by the same held-out test and BIC -> extended model (loop model file) -> report (report_json /
write_loop_report).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import stats

from robowrangler_sim.diagnose.errors import ModelMismatchError, UnknownEffectError
from robowrangler_sim.diagnose.fit import ModelFitter, jackknife_intervals
from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates import LOOP_LIBRARY, LoopCandidate
from robowrangler_sim.diagnose.loop.data import (LOOP_LENGTH_TOLERANCE, LoopData, length_mismatch_message,
                                                 load_loop_data)
from robowrangler_sim.diagnose.loop.flutter import (ContourScatter, LoopFlutterError, contour_scatter, flutter_message,
                                                    flutter_note)
from robowrangler_sim.diagnose.loop.locate import LoopLocator, frame_regimes, module_turning, part_labels
from robowrangler_sim.diagnose.loop.model_file import LoopModel
from robowrangler_sim.diagnose.loop.replay import CHANNEL, LoopReplay
from robowrangler_sim.diagnose.loop.residuals import LoopResiduals
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.diagnose.residuals import robust_scale
from robowrangler_sim.diagnose.select import ModelScore, accepted, effective_counts, equivalent, score_model

BLOCK_S = 1.0
HELDOUT_EVERY = 3
ALPHA = 0.01
PAIR_TRIGGER_NOISE = 2.0
"""Two effects together are tried when the best one (or the refitted chain, when none is accepted alone) leaves
held-out contour error above this many camera-noise sigmas (the report's own 'beyond noise'): each of the PAIR_FIRSTS
candidates with the lowest held-out error with the PAIR_PARTNERS others that could explain most of what it leaves
(linear gain on its fit residual)."""
PAIR_FIRSTS = 2
PAIR_PARTNERS = 2
PAIR_MAX_COSINE = 0.9
"""A pair is kept only when the two laws move the contours differently on this recording: the cosine between their
parameters' sensitivities (fit frames, at the pair's solution) at most this."""
WITHIN_NOISE_Z = float(stats.norm.isf(ALPHA))
"""The refitted chain leaves something beyond the camera noise only when its held-out mean square contour error
exceeds the noise's by more than this many of its sampling sd under noise alone (the locator's one-sided ALPHA):
below it, nothing is left to explain, and a law that still passes the held-out test (a 0.009 m/s wind taking
1.92 mm to 1.91 mm against 1.90 mm of noise) is fitting the chain's own form error, not physics."""
SHORT_LOOP_EXPLAINED = 0.5
"""A loop shorter than the model's is a loop effect's only when that effect at least halves the contour error."""

LOOP_NOMINAL_REFIT: tuple[ParamSpec, ...] = (
    ParamSpec("servo_time_constant_s", sm.TH_TAU_S, "s", 0.5, 2.0, 0.5, relative=True),
    ParamSpec("loop_length_scale", sm.TH_LEN_SCALE, "1", 0.95, 1.05, 1.0, relative=True),
)
"""The chain's own parameters the refit may move: its servos' kd/kp and the loop length (rope / guide calibration)."""


@dataclass
class LoopFinding:
    effect_id: str
    params: dict[str, dict]
    law: str
    part: str | None
    spans_s: list[list[float]]
    heldout_rms_mm_before: float
    heldout_rms_mm_after: float
    evidence: dict


@dataclass
class LoopDiagnosis:
    """What the loop diagnosis found; ``report`` is its report.json section."""

    recording: Path
    verdict: str
    effects: list[LoopFinding]
    not_identifiable: list[dict]
    nominal_refit: dict[str, dict]
    noise_mm: float
    located: dict
    candidates: list[dict]
    model: LoopModel
    timings_s: dict[str, float]
    notes: list[str]
    frames: int
    series: dict = field(repr=False, default_factory=dict)
    flutter: dict = field(default_factory=dict)

    @property
    def first_line(self) -> str:
        from robowrangler_sim.diagnose.loop.report import loop_first_line
        return loop_first_line(self)

    @property
    def report(self) -> dict:
        from robowrangler_sim.diagnose.loop.report import loop_report_json
        return loop_report_json(self)


def _resolve(effects) -> list[LoopCandidate]:
    if effects is None:
        return [c() for c in LOOP_LIBRARY.values()]
    out = []
    for e in effects:
        if e not in LOOP_LIBRARY:
            raise UnknownEffectError(f"effects: unknown loop effect id {e!r}; known: {', '.join(LOOP_LIBRARY)}")
        out.append(LOOP_LIBRARY[e]())
    return out


def _progress(stream, msg: str) -> None:
    if stream is not None:
        print(f"diagnose loop: {msg}", file=stream, flush=True)


def diagnose_loop(recording_path: str | Path, *, model: str | Path | LoopModel | None = None,
                  effects: list[str] | None = None, progress=None) -> LoopDiagnosis:
    """Diagnose the loop contours of one recording against the chain model (None: the nominal chain with the
    default shape table). effects: loop candidate ids (None: all). Raises DiagnoseError subclasses naming what is
    wrong (no contours, no phi, contours in another frame, too few points or frames, loop length mismatch)."""
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    cands = _resolve(effects)
    base = LoopModel.nominal() if model is None else (model if isinstance(model, LoopModel) else LoopModel.load(model))
    data = load_loop_data(recording_path, takeoff_speed_mps=base.takeoff_speed_mps(),
                          loop_length_of_guide=base.loop_length_m, defer_short_loop=True)
    shape = base.shape_model()
    replay = LoopReplay(data, shape, np.array([base.loop_length_m(g) for g in data.guide_m]))
    theta_base = base.theta(shape)
    replay.set_normals(theta_base)
    F, K = data.points_m.shape[:2]
    block_f = ((data.time_s - data.time_s[0]) // BLOCK_S).astype(int)
    held_blocks = heldout_blocks(block_f, module_turning(replay.phidot_rad_s))
    block_id = np.repeat(block_f, K)
    fit_mask = ~np.isin(block_id, held_blocks)
    timings["load_s"] = time.perf_counter() - t0
    _progress(progress, f"{data.path.name}: {F} airborne frames of {data.frames_total}, {K} points each")

    t1 = time.perf_counter()
    pred0 = replay.predict(theta_base)[CHANNEL][0]
    res0 = LoopResiduals().fit(replay, pred0)
    noise = res0.noise_m_
    scatter = contour_scatter(data.points_m, replay.normals, data.segment)
    notes = list(data.notes)
    if scatter.flutters:
        notes.append(flutter_note(scatter))
    timings["replay_s"] = time.perf_counter() - t1

    t1 = time.perf_counter()
    _progress(progress, "refitting the chain's own parameters")
    w0 = {CHANNEL: 1.0 / max(noise, 1e-5)}
    nominal = ModelFitter(list(LOOP_NOMINAL_REFIT), weights=w0).fit(replay, theta_base, fit_mask=fit_mask)
    r_nom = replay.measured()[CHANNEL] - nominal.prediction_[CHANNEL]
    sigma = max(noise, robust_scale(r_nom[fit_mask]))
    weights = {CHANNEL: 1.0 / sigma}
    nominal = ModelFitter(list(LOOP_NOMINAL_REFIT), weights=weights).fit(replay, nominal.theta_, fit_mask=fit_mask,
                                                                         bounds_ref=theta_base)
    r_nom = replay.measured()[CHANNEL] - nominal.prediction_[CHANNEL]
    n_eff = effective_counts({CHANNEL: r_nom}, fit_mask)
    sc_nom = score_model("nominal_refit", len(LOOP_NOMINAL_REFIT), {CHANNEL: r_nom}, weights, fit_mask, block_id,
                         held_blocks, n_eff)
    excess_z = heldout_excess_z(sc_nom, noise)
    timings["nominal_refit_s"] = time.perf_counter() - t1

    t1 = time.perf_counter()
    parts = part_labels(data.points_m)
    regimes = frame_regimes(data, replay.phidot_rad_s, shape.speeds)
    loc = LoopLocator(alpha=ALPHA).fit(r_nom.reshape(F, K), noise, parts, regimes, data.time_s)
    timings["locate_s"] = time.perf_counter() - t1

    t1 = time.perf_counter()
    fits: dict[str, tuple[LoopCandidate, ModelFitter, ModelScore]] = {}
    not_ident: list[dict] = []
    rows: list[dict] = [{"id": "nominal_refit", "status": "base", "heldout_rms_mm": _mm(sc_nom),
                         "heldout_excess_z": round(excess_z, 2),
                         "fit_rms_mm": round(sc_nom.fit_rms[CHANNEL] * 1e3, 3)}]
    for cand in cands:
        ident = cand.identifiable(replay)
        if not ident.identifiable:
            not_ident.append({"id": cand.effect_id, "reason": ident.reason,
                              "separating_measurement": ident.separating_measurement})
            rows.append({"id": cand.effect_id, "status": "not_identifiable", "reason": ident.reason})
            continue
        _progress(progress, f"fitting {cand.effect_id}")
        th_c = cand.apply_neutral(nominal.theta_)
        cols, starts = cand.start_grid(th_c)
        fitter = ModelFitter(list(LOOP_NOMINAL_REFIT) + list(cand.params), weights=weights, max_nfev=15).fit(
            replay, th_c, fit_mask=fit_mask, starts=starts, start_columns=cols, bounds_ref=theta_base)
        r_c = replay.measured()[CHANNEL] - fitter.prediction_[CHANNEL]
        sc = score_model(cand.effect_id, len(LOOP_NOMINAL_REFIT) + len(cand.params), {CHANNEL: r_c}, weights,
                         fit_mask, block_id, held_blocks, n_eff)
        ok, ev = accepted(sc, sc_nom)
        fits[cand.effect_id] = (cand, fitter, sc)
        own = {s.name for s in cand.params}
        status = "rejected" if not ok else ("accepted" if excess_z > WITHIN_NOISE_Z else "within_noise")
        rows.append({"id": cand.effect_id, "status": status, **ev,
                     "heldout_rms_mm": _mm(sc),
                     "params": {p.name: round(p.value, 6) for p in fitter.params_ if p.name in own}})
    timings["candidates_s"] = time.perf_counter() - t1

    t1 = time.perf_counter()
    ok_ids = sorted([r["id"] for r in rows if r["status"] == "accepted"], key=lambda i: fits[i][2].block_sse.sum())
    verdict, chosen, chosen_fit, chosen_sc = "none", [], nominal, sc_nom
    if ok_ids:
        best = ok_ids[0]
        rivals = [o for o in ok_ids[1:] if equivalent(fits[best][2], fits[o][2])]
        chosen, chosen_fit, chosen_sc = [best], fits[best][1], fits[best][2]
        if rivals:
            verdict = "not_identifiable"
            names = [best] + rivals
            not_ident.insert(0, {"id": " / ".join(names), "candidates": names,
                                 "reason": "these candidates explain the contours equally well on held-out frames",
                                 "separating_measurement": "; ".join(f"{i}: {fits[i][0].separating_measurement}"
                                                                     for i in names)})
        else:
            verdict = "missing_physics"
    pair_ev: dict | None = None
    single_rms = chosen_sc.heldout_rms[CHANNEL]
    if single_rms > PAIR_TRIGGER_NOISE * noise and excess_z > WITHIN_NOISE_Z and len(fits) >= 2:
        # one effect does not bring the contours down to the camera noise (or none is accepted alone): two together
        ranked = sorted(fits, key=lambda i: fits[i][2].block_sse.sum())
        firsts = ranked[:PAIR_FIRSTS]
        if chosen and chosen[0] not in firsts:
            firsts = [chosen[0]] + firsts[:-1]
        pairs: list[tuple[str, str]] = []
        for first in firsts:  # forward step: the partners that could explain most of what the first one leaves
            gains = {o: _partner_gain(replay, fits[first][1], fits[o][0], fit_mask) for o in fits if o != first}
            for o in sorted(gains, key=gains.get, reverse=True)[:PAIR_PARTNERS]:
                if gains[o] > 0 and (first, o) not in pairs and (o, first) not in pairs:
                    pairs.append((first, o))
        ok_pairs: list[tuple] = []
        for first, other in pairs:
            _progress(progress, f"fitting {first} + {other} together")
            c1, c2 = fits[first][0], fits[other][0]
            th_p = c2.apply_neutral(fits[first][1].theta_)
            cols, starts = c2.start_grid(th_p)
            specs = list(LOOP_NOMINAL_REFIT) + list(c1.params) + list(c2.params)
            fp = ModelFitter(specs, weights=weights, max_nfev=15).fit(replay, th_p, fit_mask=fit_mask, starts=starts,
                                                                      start_columns=cols, bounds_ref=theta_base)
            r_p = replay.measured()[CHANNEL] - fp.prediction_[CHANNEL]
            sc_p = score_model(f"{first}+{other}", len(specs), {CHANNEL: r_p}, weights, fit_mask, block_id,
                               held_blocks, n_eff)
            # the pair must beat the better of its two alone and the single-effect verdict (or the refitted chain)
            ok, ev = accepted(sc_p, fits[first][2])
            ok = ok and accepted(sc_p, chosen_sc)[0]
            ev["sensitivity_cosine"] = round(_sensitivity_cosine(replay, fp.theta_, c1, c2, fit_mask), 4)
            if abs(ev["sensitivity_cosine"]) > PAIR_MAX_COSINE:
                ok = False  # the two laws move the contours alike here: their parameters trade, the pair is not separable
            own = {x.name for x in c1.params} | {x.name for x in c2.params}
            rows.append({"id": f"{first}+{other}", "status": "accepted" if ok else "rejected", **ev,
                         "heldout_rms_mm": _mm(sc_p), "against": first,
                         "params": {q.name: round(q.value, 6) for q in fp.params_ if q.name in own}})
            if ok:
                ok_pairs.append((first, other, fp, sc_p, ev))
        if ok_pairs:
            ok_pairs.sort(key=lambda q: q[3].block_sse.sum())
            best_pair = ok_pairs[0]
            rivals = [q for q in ok_pairs[1:] if equivalent(best_pair[3], q[3])]
            if not_ident and "candidates" in not_ident[0]:
                not_ident.pop(0)
            chosen, chosen_fit, chosen_sc, pair_ev = [best_pair[0], best_pair[1]], best_pair[2], best_pair[3], best_pair[4]
            if rivals:
                verdict = "not_identifiable"
                names = [f"{q[0]}+{q[1]}" for q in [best_pair] + rivals]
                ids = list(dict.fromkeys(i for q in [best_pair] + rivals for i in q[:2]))
                not_ident.insert(0, {"id": " / ".join(names), "candidates": names,
                                     "reason": "these pairs of effects explain the contours equally well on held-out "
                                               "frames",
                                     "separating_measurement": "; ".join(f"{i}: {fits[i][0].separating_measurement}"
                                                                         for i in ids)})
            else:
                verdict = "missing_physics"
    timings["select_s"] = time.perf_counter() - t1
    if abs(data.length_ratio - 1.0) > LOOP_LENGTH_TOLERANCE:
        _check_short_loop_explained(data, base, replay, theta_base, scatter, verdict, chosen, sc_nom, chosen_sc)

    effects_out: list[LoopFinding] = []
    if verdict == "missing_physics":
        _progress(progress, "intervals (jackknife)")
        cands_chosen = [fits[i][0] for i in chosen]
        own_all = {x.name for c in cands_chosen for x in c.params}
        jackknife_intervals(chosen_fit, own_all, max_nfev=4)
        r_after = replay.measured()[CHANNEL] - chosen_fit.prediction_[CHANNEL]
        gain = (r_nom ** 2 - r_after ** 2).reshape(F, K)
        part_gain = {}
        for p_i, p_name in enumerate(("near_exit", "upper_branch", "tip", "lower_branch")):
            m = parts == p_i
            part_gain[p_name] = float(gain[m].sum())
        part = max(part_gain, key=part_gain.get)
        for j, cand in enumerate(cands_chosen):
            own = {x.name for x in cand.params}
            ev = next(r for r in rows if r["id"] == cand.effect_id) if j == 0 and pair_ev is None else pair_ev
            effects_out.append(LoopFinding(
                effect_id=cand.effect_id, law=cand.law, part=part, spans_s=[s[:2] for s in loc.spans_],
                params={p.name: {"value": p.value, "unit": p.unit, "ci95": list(p.ci95)}
                        for p in chosen_fit.params_ if p.name in own},
                heldout_rms_mm_before=_mm(sc_nom), heldout_rms_mm_after=_mm(chosen_sc),
                evidence={"delta_bic": ev["delta_bic"], "heldout_lr": ev["heldout_lr"], "heldout_p": ev["heldout_p"],
                          **({"pair_against_single": chosen[0]} if pair_ev is not None else {})}))
    nominal_refit = {p.name: {"nominal": float(theta_base[s.column]), "fitted": p.value, "unit": p.unit,
                              "ci95": list(p.ci95)}
                     for p, s in zip(nominal.params_, nominal.specs)}
    model_out = base.extended(chosen_fit.theta_, effects=chosen if verdict == "missing_physics" else [],
                              recording=str(data.path))
    timings["total_s"] = time.perf_counter() - t0
    located = {"part": loc.part_, "cells": loc.cells_, "spans_s": loc.spans_}
    return LoopDiagnosis(
        recording=data.path, verdict=verdict, effects=effects_out, not_identifiable=not_ident,
        nominal_refit=nominal_refit, noise_mm=round(noise * 1e3, 3), located=located, candidates=rows,
        model=model_out, timings_s=timings, notes=notes, frames=F, flutter=scatter.report(),
        series={"time_s": data.time_s, "heldout": ~fit_mask.reshape(F, K)[:, 0],
                "rms_before_mm": np.sqrt(np.mean(r_nom.reshape(F, K) ** 2, axis=1)) * 1e3,
                "rms_after_mm": np.sqrt(np.mean((replay.measured()[CHANNEL]
                                                 - chosen_fit.prediction_[CHANNEL]).reshape(F, K) ** 2, axis=1)) * 1e3,
                "observed": data.points_m, "nominal_theta": theta_base, "after_theta": chosen_fit.theta_,
                "replay": replay})


def heldout_blocks(block_f: np.ndarray, turning_f: np.ndarray) -> np.ndarray:
    """The held-out blocks: every HELDOUT_EVERY-th block among those where the module turns (turning_f: per
    frame) and, apart, among the others; of two blocks of a kind, the second. A law for what happens in a turn is
    then tested on a turn it was not fitted to: with every third block of the whole run, the held-out blocks of a
    recording with two short turns held only their settled ends, where a wave law and a normal drag law, or a wave
    law and nothing at all, tie. (Speed steps were counted apart too at first: on a recording of C_f changed, flown
    at 4, 4.5 and 5 m/s, that held out the last 5 m/s second, where a changed C_f makes the truth's loop flutter,
    and no law passed; a speed step's law is a steady shape, tested by the steady blocks at other speeds.) Fewer
    than two blocks held out: every other one."""
    n_blocks = int(block_f.max()) + 1
    turning_b = np.zeros(n_blocks, dtype=bool)
    turning_b[block_f[turning_f]] = True
    held: list[int] = []
    for kind in (turning_b, ~turning_b):
        ids = np.flatnonzero(kind)
        pick = ids[HELDOUT_EVERY - 1::HELDOUT_EVERY]
        held += list(pick if pick.size or ids.size < 2 else ids[-1:])
    out = np.array(sorted(held), dtype=int)
    return out if out.size >= 2 else np.arange(1, n_blocks, 2)


def heldout_excess_z(sc: ModelScore, noise_m: float) -> float:
    """How far a model's held-out mean square contour error lies above the camera noise's, in units of its sampling
    sd under noise alone: (rms^2 / noise^2 - 1) / sqrt(2 / N), N the held-out blocks' independent samples."""
    n = max(float(sc.heldout_n_eff[CHANNEL]), 1.0)
    return float(((sc.heldout_rms[CHANNEL] / max(noise_m, 1e-9)) ** 2 - 1.0) / np.sqrt(2.0 / n))


def _partner_gain(replay: LoopReplay, first_fit: ModelFitter, partner: LoopCandidate, fit_mask: np.ndarray) -> float:
    """How much of the first effect's fit residual the partner's law could take (least-squares gain of the partner's
    contour change, best over its start points, on the fit frames), m^2."""
    theta = partner.apply_neutral(first_fit.theta_)
    cols, starts = partner.start_grid(theta)
    rows = np.repeat(theta[None, :], starts.shape[0] + 1, axis=0)
    rows[1:, cols] = starts
    pred = replay.predict(rows)[CHANNEL]
    r = (replay.measured()[CHANNEL] - pred[0])[fit_mask]
    best = 0.0
    for d in pred[1:]:
        dd = (d - pred[0])[fit_mask]
        n2 = float(dd @ dd)
        if n2 > 0:
            best = max(best, float(dd @ r) ** 2 / n2)
    return best


def _sensitivity_cosine(replay: LoopReplay, theta: np.ndarray, c1: LoopCandidate, c2: LoopCandidate,
                        fit_mask: np.ndarray) -> float:
    """Cosine between the contour changes of a small step (a tenth of the typical magnitude) in each law's parameter."""
    rows = np.repeat(theta[None, :], 3, axis=0)
    for i, spec in enumerate((c1.params[0], c2.params[0]), start=1):
        rows[i, spec.column] += 0.1 * spec.scale
    pred = replay.predict(rows)[CHANNEL]
    a, b = (pred[1] - pred[0])[fit_mask], (pred[2] - pred[0])[fit_mask]
    den = float(np.linalg.norm(a) * np.linalg.norm(b))
    return float(a @ b) / den if den > 0 else 1.0


def _check_short_loop_explained(data: LoopData, base: LoopModel, replay: LoopReplay, theta_base: np.ndarray,
                                scatter: ContourScatter, verdict: str, chosen: list[str], sc_nom: ModelScore,
                                chosen_sc: ModelScore) -> None:
    """A loop shorter than the model's (kept by the loader) stands only when a loop effect explains the contours:
    named or not identifiable among candidates, and held-out contour error at most SHORT_LOOP_EXPLAINED x the
    refitted chain's. Else: LoopFlutterError when the contour flutters unevenly (flutter.py: the rope folds on part of
    the loop, e.g. in a head wind; outside the library's steady laws), ModelMismatchError (the rope length or guide
    calibration) when it is steady, as the loader would."""
    before, after = _mm(sc_nom), _mm(chosen_sc)
    if verdict != "none" and after <= SHORT_LOOP_EXPLAINED * before:
        return
    what = (f"the best loop effect, {chosen[0]}, takes the held-out contour error only from {before:.1f} to "
            f"{after:.1f} mm" if chosen else f"no loop effect explains the contours (held-out contour error "
                                              f"{before:.1f} mm)")
    head = length_mismatch_message(data, base.loop_length_m, data.length_ratio, calibration=False)
    if scatter.flutters:
        reach_model = float(np.median(replay.contours(theta_base[None, :])[0][:, :, 0].max(axis=1)))
        raise LoopFlutterError(head + flutter_message(scatter, reach_observed_m=float(np.median(
            data.points_m[:, :, 0].max(axis=1))), reach_model_m=reach_model) + f"; {what}")
    raise ModelMismatchError(length_mismatch_message(data, base.loop_length_m, data.length_ratio)
                             + f"; {what}, and the contour is steady (it scatters evenly along the loop, "
                               f"{scatter.lower_quartile_m * 1e3:.1f}-{scatter.p90_m * 1e3:.1f} mm from frame to "
                               "frame), not a loop that folds and flutters")


def _mm(sc: ModelScore) -> float:
    return round(sc.heldout_rms[CHANNEL] * 1e3, 3)
