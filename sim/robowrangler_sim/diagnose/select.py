"""Select: which fitted model the recording supports, on held-out spans and an information criterion.

A candidate (or a pair) is accepted over the refitted nominal model only if both hold:
  * BIC on the fit samples drops by more than 10 (strong evidence; Gaussian likelihood with each channel's
    variance estimated, sample counts corrected for autocorrelation, k ln N_eff for its extra parameters);
  * on the held-out blocks, which no fit saw, it predicts better by the same measure: twice the log-likelihood
    ratio, sum over channels of N_eff,held ln(loss_base / loss_candidate), above 10. N_eff,held is the held-out
    sample count times the share of independent samples the fit set had (the base model's residual), so both
    criteria count evidence alike. A held-out likelihood ratio weighs how much better a model predicts, not only
    how consistently (a Diebold-Mariano test calls a 1e-10 gain kept on every sample significant, and a halved
    error confined to one load step not); the Diebold-Mariano p is still reported.
Nothing accepted -> "none". The best accepted one is "not identifiable" when another accepted candidate
predicts the held-out blocks as well (held-out ratio between the two within 10, and BIC within 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from robowrangler_sim.diagnose.fit import huber
from robowrangler_sim.diagnose.residuals import effective_fraction

HUBER_SCALE = 3.0
BIC_STRONG = 10.0
HELDOUT_STRONG = 10.0  # 2 ln(held-out likelihood ratio): the same "very strong" level as the BIC's (Kass & Raftery)


@dataclass
class ModelScore:
    """A fitted model's score. block_sse (n_heldout,) Huber loss per held-out sample; bic on the fit set;
    heldout_loss: channel -> mean Huber loss on its held-out samples; heldout_n_eff: channel -> independent
    held-out samples (the fit set's independent share of the base model's residual)."""

    name: str
    n_params: int
    bic: float
    block_sse: np.ndarray
    heldout_rms: dict[str, float]
    fit_rms: dict[str, float]
    heldout_loss: dict[str, float]
    heldout_n_eff: dict[str, float]


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
    loss: dict[str, float] = {}
    n_held: dict[str, float] = {}
    for c, r in residuals.items():
        z = huber(r * weights[c], HUBER_SCALE)
        sse += z[held]
        m = held & ok[c]
        loss[c] = float(np.mean(z[m])) if m.any() else float("nan")
        n_fit = int((fit_mask & ok[c]).sum())
        n_held[c] = n_eff[c] * int(m.sum()) / n_fit if n_fit else 0.0

    def rms(r, m):
        return float(np.sqrt(np.mean(r[m] ** 2))) if m.any() else float("nan")

    return ModelScore(name, n_params, float(bic), sse,
                      {c: rms(r, held & ok[c]) for c, r in residuals.items()},
                      {c: rms(r, fit_mask & ok[c]) for c, r in residuals.items()}, loss, n_held)


def heldout_lr(better: ModelScore, worse: ModelScore) -> float:
    """2 ln of the held-out likelihood ratio of `better` over `worse` (Gaussian, each channel's variance its mean
    Huber loss, independent samples N_eff,held of `worse`): positive when `better` predicts the held-out blocks
    better. A channel neither observes on held-out samples adds nothing."""
    total = 0.0
    for c, n in worse.heldout_n_eff.items():
        a, b = worse.heldout_loss.get(c, np.nan), better.heldout_loss.get(c, np.nan)
        if n > 0 and np.isfinite(a) and np.isfinite(b) and a > 0 and b > 0:
            total += n * float(np.log(a / b))
    return total


def equivalent(a: ModelScore, b: ModelScore) -> bool:
    """Two models the recording cannot tell apart: held-out likelihood ratio and BIC both within the strong
    level."""
    return abs(heldout_lr(a, b)) < HELDOUT_STRONG and abs(a.bic - b.bic) < BIC_STRONG


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


def accepted(candidate: ModelScore, base: ModelScore) -> tuple[bool, dict[str, float]]:
    """The candidate beats the base on the fit set (BIC) and on the held-out blocks (likelihood ratio)."""
    d_bic = candidate.bic - base.bic
    lr = heldout_lr(candidate, base)
    p = heldout_p(candidate, base)
    return (bool(d_bic < -BIC_STRONG and lr > HELDOUT_STRONG),
            {"delta_bic": float(d_bic), "heldout_lr": float(lr), "heldout_p": float(p)})


def reduces_own_channel(cand, score: ModelScore, base: ModelScore) -> bool:
    """Whether a law (a Candidate, or its class) lowers the held-out RMS of the channel it shows in first (its
    channels[0]: the rope speed for all but the battery's sag), the error the report's first line quotes. The
    acceptance rule weighs each sample by its noise and timing uncertainty, so a law can win there on a few samples
    while the error users read rises (a latency "found" at 140 -> 142 mm/s where a dead band acts only in the
    spin-down): that is not a finding."""
    c = cand.channels[0]
    return c not in base.heldout_rms or score.heldout_rms[c] < base.heldout_rms[c]
