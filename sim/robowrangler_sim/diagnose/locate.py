"""Locate: where (channel, time span) the residual stands out, with its significance against the noise.

Windows of ``window_s``; in each, the residual's mean square over the robust residual scale (1.4826 MAD)
is compared with its chi-square quantile for the window's effective sample count (autocorrelation
corrected); windows past the 1 - alpha quantile (alpha Bonferroni-divided by the windows) are flagged and
merged into spans. ``signed`` spans use the window's mean instead (t statistic), for one-sided effects
such as an external load (speed below the model).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from robowrangler_sim.diagnose.residuals import effective_fraction


@dataclass(frozen=True)
class Span:
    channel: str
    t0_s: float
    t1_s: float
    significance: float  # the largest window statistic over its threshold (> 1 = significant)
    sign: int  # +1 recording above the model, -1 below, 0 both


def _windows(n: int, w: int) -> list[tuple[int, int]]:
    return [(k, min(n, k + w)) for k in range(0, n, w) if min(n, k + w) - k >= max(3, w // 2)]


def _merge(flags: list[tuple[int, int, float, int]], t: np.ndarray, channel: str, bridge_s: float) -> list[Span]:
    spans: list[Span] = []
    for a, b, sig, sign in flags:
        t0, t1 = float(t[a]), float(t[b - 1])
        if spans and spans[-1].t1_s >= t0 - bridge_s and spans[-1].sign == sign:
            last = spans[-1]
            spans[-1] = Span(channel, last.t0_s, t1, max(last.significance, sig), sign)
        else:
            spans.append(Span(channel, t0, t1, sig, sign))
    return spans


class Locator:
    """Estimator: fit(t_s, residuals) -> spans_ (list of Span), window_stat_ per channel.

    Args: window_s: window length; alpha: family-wise false-flag rate per channel; signed: one-sided mean test;
    bridge_s: flagged windows this close are one span (bridges the held-out blocks when only fit samples are given).
    """

    def __init__(self, *, window_s: float = 0.4, alpha: float = 0.01, signed: bool = False,
                 bridge_s: float = 0.0) -> None:
        if window_s <= 0 or not 0 < alpha < 1:
            raise ValueError(f"window_s > 0 and 0 < alpha < 1 expected, got {window_s}, {alpha}")
        self.window_s = window_s
        self.alpha = alpha
        self.signed = signed
        self.bridge_s = bridge_s

    def fit(self, t_s: np.ndarray, residuals: dict[str, np.ndarray]) -> Locator:
        dt = float(np.median(np.diff(t_s)))
        w = max(3, int(round(self.window_s / dt)))
        self.spans_: list[Span] = []
        self.window_stat_: dict[str, list[tuple[float, float, float]]] = {}
        for channel, r in residuals.items():
            scale = 1.4826 * float(np.median(np.abs(r - np.median(r))))
            if scale <= 0:
                scale = float(np.std(r)) or 1e-12
            frac = effective_fraction(r)
            wins = _windows(r.size, w)
            a = self.alpha / max(1, len(wins))
            flags = []
            stat_list = []
            for i0, i1 in wins:
                seg = r[i0:i1]
                n_eff = max(1.0, seg.size * frac)
                if self.signed:
                    tstat = float(seg.mean()) / (scale / np.sqrt(n_eff))
                    thr = float(stats.norm.ppf(1 - a))
                    sig = abs(tstat) / thr
                    sign = 1 if tstat > 0 else -1
                else:
                    ms = float(np.mean(seg ** 2)) / scale ** 2
                    thr = float(stats.chi2.ppf(1 - a, n_eff)) / n_eff
                    sig = ms / thr
                    sign = 0
                stat_list.append((float(t_s[i0]), float(t_s[i1 - 1]), sig))
                if sig > 1.0:
                    flags.append((i0, i1, sig, sign))
            self.window_stat_[channel] = stat_list
            self.spans_.extend(_merge(flags, t_s, channel, self.bridge_s + 1.5 * dt))
        return self


def spans_mask(t_s: np.ndarray, spans: list[tuple[float, float]]) -> np.ndarray:
    m = np.zeros(t_s.shape, dtype=bool)
    for t0, t1 in spans:
        m |= (t_s >= t0) & (t_s <= t1)
    return m


def iou_s(a: list[tuple[float, float]], b: list[tuple[float, float]], *, dt_s: float = 0.01) -> float:
    """Intersection over union of two span lists on a dt_s grid."""
    if not a and not b:
        return 1.0
    ends = [x for s in a + b for x in s]
    grid = np.arange(min(ends), max(ends) + dt_s, dt_s)
    ma, mb = spans_mask(grid, a), spans_mask(grid, b)
    union = np.sum(ma | mb)
    return float(np.sum(ma & mb) / union) if union else 0.0
