"""Select: which fitted model the recording supports, on held-out spans and an information criterion.

A candidate (or a pair) is accepted over the refitted nominal model only if both hold:
  * BIC on the fit samples drops by more than 10 (strong evidence; Gaussian likelihood with each channel's
    variance estimated, sample counts corrected for autocorrelation, k ln N_eff for its extra parameters);
  * on the held-out blocks it predicts better: a one-sided Diebold-Mariano test on the per-sample loss
    difference (Newey-West variance, so correlated samples are not counted as independent), p < alpha.
Nothing accepted -> "none". The best accepted one is "not identifiable" when another accepted candidate
predicts the held-out blocks as well (paired test between the two, p >= alpha, and BIC within 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from robowrangler_sim.diagnose.fit import huber
from robowrangler_sim.diagnose.residuals import effective_fraction

HUBER_SCALE = 3.0
BIC_STRONG = 10.0


@dataclass
class ModelScore:
    """A fitted model's score. block_sse (n_heldout,) Huber loss per held-out sample; bic on the fit set."""

    name: str
    n_params: int
    bic: float
    block_sse: np.ndarray
    heldout_rms: dict[str, float]
    fit_rms: dict[str, float]


def effective_counts(residuals: dict[str, np.ndarray], fit_mask: np.ndarray, *,
                     valid: dict[str, np.ndarray] | None = None) -> dict[str, float]:
    """Independent-sample count per channel on the fit set (from the base model's residual, then shared by
    every model compared with it, so their BICs are on one scale). valid: channel -> (S,) observed samples."""
    out = {}
    for c, r in residuals.items():
        m = fit_mask & (valid[c] if valid is not None and c in valid else True)
        out[c] = max(2.0, float(m.sum()) * effective_fraction(r[m]))
    return out


def score_model(name: str, n_params: int, residuals: dict[str, np.ndarray], weights: dict[str, float],
                fit_mask: np.ndarray, block_id: np.ndarray, heldout_blocks: np.ndarray,
                n_eff: dict[str, float], *, valid: dict[str, np.ndarray] | None = None) -> ModelScore:
    """residuals: channel -> (S,) recording - model; weights: channel -> (S,) 1/sigma per sample. block_id: (S,)
    block index of each sample. n_eff: effective_counts of the base model. Scores use the Huber rho of the
    weighted residual (the fit's own loss), so step-edge samples weigh as in the fit."""
    ok = {c: (valid[c] if valid is not None and c in valid else np.ones(r.shape, dtype=bool))
          for c, r in residuals.items()}
    bic = 0.0
    n_eff_total = 0.0
    for c, r in residuals.items():
        z = huber(r * weights[c], HUBER_SCALE)
        n_c = n_eff[c]
        bic += n_c * np.log(max(float(np.mean(z[fit_mask & ok[c]])), 1e-30))
        n_eff_total += n_c
    bic += n_params * np.log(n_eff_total)
    held = np.isin(block_id, heldout_blocks)
    sse = np.zeros(int(held.sum()))
    for c, r in residuals.items():
        sse += huber(r * weights[c], HUBER_SCALE)[held]

    def rms(r, m):
        return float(np.sqrt(np.mean(r[m] ** 2))) if m.any() else float("nan")

    return ModelScore(name, n_params, float(bic), sse,
                      {c: rms(r, held & ok[c]) for c, r in residuals.items()},
                      {c: rms(r, fit_mask & ok[c]) for c, r in residuals.items()})


def heldout_p(better: ModelScore, worse: ModelScore, *, max_lag: int = 25) -> float:
    """One-sided Diebold-Mariano test that `better` has the smaller held-out loss (p-value): d = per-sample
    loss difference, variance of its mean by Newey-West with Bartlett weights up to max_lag samples."""
    d = worse.block_sse - better.block_sse
    n = d.size
    if n < 10 or np.all(d == 0):
        return 1.0
    dc = d - d.mean()
    var = float(dc @ dc) / n
    for lag in range(1, min(max_lag, n - 1) + 1):
        var += 2.0 * (1.0 - lag / (max_lag + 1)) * float(dc[lag:] @ dc[:-lag]) / n
    if var <= 0:
        return 0.0 if d.mean() > 0 else 1.0
    z = d.mean() / np.sqrt(var / n)
    return float(stats.norm.sf(z))


def accepted(candidate: ModelScore, base: ModelScore, *, alpha: float) -> tuple[bool, dict[str, float]]:
    d_bic = candidate.bic - base.bic
    p = heldout_p(candidate, base)
    better = candidate.block_sse.sum() < base.block_sse.sum()
    return bool(d_bic < -BIC_STRONG and p < alpha and better), {"delta_bic": float(d_bic), "heldout_p": float(p)}
