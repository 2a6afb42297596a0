"""What a diagnosis states about a fitted model: an effect it found (EffectFinding) and the nominal refit's table.

One builder for the drive (api.py) and the spindle half (spindle_stage.py): a chosen candidate's parameters with
their 95 % intervals, located spans and regime, held-out RMS before/after and the selection's evidence; and each
refitted nominal parameter as {nominal, fitted, unit, ci95}.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robowrangler_sim.diagnose.locate import spans_mask
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.diagnose.regimes import dominant_regime


@dataclass
class EffectFinding:
    """A fitted candidate as the report states it."""

    effect_id: str
    params: dict[str, dict]
    channels: list[str]
    spans_s: list[list[float]]
    regime: dict
    heldout_rms_before: dict[str, float]
    heldout_rms_after: dict[str, float]
    evidence: dict
    law: str


def effect_params(fitter, cand) -> dict[str, dict]:
    """The candidate's own parameters of a fit: {name: {value, unit, ci95}}."""
    own = {s.name for s in cand.params}
    return {p.name: {"value": p.value, "unit": p.unit, "ci95": list(p.ci95)} for p in fitter.params_ if p.name in own}


def effect_finding(cand, params: dict[str, dict], *, spans_s: list[list[float]], labels: dict[str, np.ndarray],
                   time_s: np.ndarray, rows: list[dict], before: dict[str, float],
                   after: dict[str, float], row_id: str | None = None, gate=None) -> EffectFinding:
    """The finding of a chosen candidate: its regime is the dominant one (labels on time_s) over spans_s, and the
    gate's (gates.RegimeGate) when the law was confined to one; its evidence the candidate's row of the selection
    (rows: the candidate table, one dict with "id" per fit; row_id: that row's id, default the effect id)."""
    ev = next(r for r in rows if r["id"] == (row_id or cand.effect_id))
    regime = dominant_regime(labels, spans_mask(time_s, [tuple(s) for s in spans_s]))
    if gate is not None:
        regime = {"acts": gate.description, **regime}
    return EffectFinding(
        effect_id=cand.effect_id, params=params, channels=list(cand.channels), spans_s=spans_s,
        regime=regime,
        heldout_rms_before=before, heldout_rms_after=after,
        evidence={"delta_bic": ev["delta_bic"], "heldout_lr": ev["heldout_lr"], "heldout_p": ev["heldout_p"]}, law=cand.law)


def nominal_refit_table(fitter, specs: tuple[ParamSpec, ...] | list[ParamSpec], theta_base: np.ndarray) -> dict:
    """Each refitted nominal parameter: {nominal (theta_base), fitted, unit, ci95}."""
    by_name = {s.name: s for s in specs}
    return {p.name: {"nominal": float(theta_base[by_name[p.name].column]), "fitted": p.value, "unit": p.unit,
                     "ci95": list(p.ci95)} for p in fitter.params_}
