"""Locate on the loop: which part of the loop (near the exit, upper branch, tip, lower branch), which phi band,
speed band and motion regime (steady / transient), and which time spans the residual stands out in, with its
significance against the contour noise.

Per cell the mean square of the residual over the noise variance is compared with its chi-square quantile for the
cell's effective sample count (neighbouring points and frames are correlated: the count is corrected by the
lag-1 autocorrelation along the points and along time); significance = statistic / threshold (> 1: flagged),
alpha Bonferroni-divided over the cells of each kind. The camera sees the loop plane only: an out-of-plane
mismatch is reported as not observable.
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from robowrangler_sim.diagnose.residuals import effective_fraction

PARTS = ("near_exit", "upper_branch", "tip", "lower_branch")
PHI_BAND_DEG = 10.0
EXIT_POINTS_FRACTION = 0.1
TIP_HALF_WIDTH_FRACTION = 0.1
PHIDOT_TRANSIENT_RAD_S = np.deg2rad(5.0)
SPEED_RATE_TRANSIENT_MPS2 = 0.5
WINDOW_S = 0.5


def part_labels(points_m: np.ndarray) -> np.ndarray:
    """(F, K) part index per point: near the exit (first and last 10 % of the arc), tip (within 10 % of the arc of
    the point farthest from the exit), upper branch (before the tip), lower branch (after)."""
    F, K = points_m.shape[:2]
    tip = np.argmax(np.linalg.norm(points_m, axis=-1), axis=1)  # (F,)
    k = np.arange(K)[None, :]
    n_exit = max(1, int(round(EXIT_POINTS_FRACTION * K)))
    half = max(1, int(round(TIP_HALF_WIDTH_FRACTION * K)))
    lab = np.where(k < tip[:, None], 1, 3)
    lab = np.where(np.abs(k - tip[:, None]) <= half, 2, lab)
    lab = np.where((k < n_exit) | (k >= K - n_exit), 0, lab)
    return lab


def module_turning(phidot_rad_s: np.ndarray) -> np.ndarray:
    """Per frame: whether the module turns fast enough to count as a transient."""
    return np.abs(phidot_rad_s) > PHIDOT_TRANSIENT_RAD_S


def inputs_changing(data, phidot_rad_s: np.ndarray) -> np.ndarray:
    """Per frame: whether the module turns or the rope speed changes (the chain's inputs moving)."""
    dv = np.zeros_like(data.speed_mps)
    for s in np.unique(data.segment):
        m = np.flatnonzero(data.segment == s)
        if m.size >= 2:
            dv[m] = np.gradient(data.speed_mps[m], data.time_s[m])
    return module_turning(phidot_rad_s) | (np.abs(dv) > SPEED_RATE_TRANSIENT_MPS2)


def frame_regimes(data, phidot_rad_s: np.ndarray, speeds_table: np.ndarray) -> dict[str, np.ndarray]:
    """Per frame: phi band, speed band (the shape table's speed intervals), motion (steady / transient)."""
    lo = np.floor(np.rad2deg(data.phi_rad) / PHI_BAND_DEG) * PHI_BAND_DEG
    phi_band = np.array([f"{a:+.0f}..{a + PHI_BAND_DEG:+.0f} deg" for a in lo])
    edges = list(speeds_table)
    names = []
    for v in data.speed_mps:
        j = int(np.searchsorted(edges, v, side="right"))
        if j == 0:
            names.append(f"< {edges[0]:g} m/s")
        elif j == len(edges):
            names.append(f">= {edges[-1]:g} m/s")
        else:
            names.append(f"{edges[j - 1]:g}-{edges[j]:g} m/s")
    moving = inputs_changing(data, phidot_rad_s)
    # a transient lasts as long as the chain takes to follow (about 3 tau = 1.5 s after the input stops)
    after = np.zeros_like(moving)
    last = -np.inf
    for i, t in enumerate(data.time_s):
        if moving[i]:
            last = t
        after[i] = t - last <= 1.5
    return {"phi_band": phi_band, "speed_band": np.array(names),
            "motion": np.where(after, "transient", "steady")}


def _cell_stat(r: np.ndarray, noise_m: float, frac: float, alpha: float) -> tuple[float, float, float]:
    """(significance, rms, mean) of residuals r against the noise."""
    n_eff = max(1.0, r.size * frac)
    ms = float(np.mean(r ** 2)) / noise_m ** 2
    thr = float(stats.chi2.ppf(1 - alpha, n_eff)) / n_eff
    return ms / thr, float(np.sqrt(np.mean(r ** 2))), float(np.mean(r))


class LoopLocator:
    """Estimator: fit(residuals (F, K), noise_m, parts (F, K), regimes, time_s) -> cells_ (list of dicts: kind, label,
    significance, rms_mm, mean_mm, flagged), spans_ (time spans [t0, t1] with significance), part_ (the part with the
    largest significant excess, or None).

    Args: alpha: family-wise false-flag rate per kind of cell.
    """

    def __init__(self, *, alpha: float = 0.01) -> None:
        self.alpha = alpha

    def fit(self, residuals: np.ndarray, noise_m: float, parts: np.ndarray, regimes: dict[str, np.ndarray],
            time_s: np.ndarray) -> LoopLocator:
        r = np.asarray(residuals)
        F, K = r.shape
        frac_pts = np.mean([effective_fraction(r[f]) for f in range(0, F, max(1, F // 50))])
        frac_t = np.mean([effective_fraction(r[:, k]) for k in range(K)])
        frac = max(frac_pts * frac_t, 1.0 / r.size)
        self.cells_: list[dict] = []
        kinds = {"part": [(PARTS[p], parts == p) for p in range(len(PARTS))]}
        for kind, lab in regimes.items():
            kinds[kind] = [(str(v), np.broadcast_to((lab == v)[:, None], r.shape)) for v in np.unique(lab)]
        for kind, cells in kinds.items():
            a = self.alpha / max(1, len(cells))
            for label, m in cells:
                if m.sum() < 3:
                    continue
                sig, rms, mean = _cell_stat(r[m], noise_m, frac, a)
                self.cells_.append({"kind": kind, "label": label, "significance": round(sig, 2),
                                    "rms_mm": round(rms * 1e3, 2), "mean_mm": round(mean * 1e3, 2),
                                    "samples": int(m.sum()), "flagged": bool(sig > 1.0)})
        self.cells_.append({"kind": "plane", "label": "out_of_plane", "significance": None, "flagged": False,
                            "note": "not observable: the contours are 2-D in the loop plane"})
        flagged_parts = [c for c in self.cells_ if c["kind"] == "part" and c["flagged"]]
        # the part: where the excess mean square over the noise is largest
        self.part_ = (max(flagged_parts, key=lambda c: c["rms_mm"])["label"] if flagged_parts else None)
        # time spans: windows of WINDOW_S with a significant excess, merged
        dt = float(np.median(np.diff(time_s))) if time_s.size > 1 else 1.0
        w = max(2, int(round(WINDOW_S / dt)))
        wins = [(i, min(F, i + w)) for i in range(0, F, w)]
        a = self.alpha / max(1, len(wins))
        spans: list[list[float]] = []
        for i0, i1 in wins:
            sig, _, _ = _cell_stat(r[i0:i1], noise_m, frac, a)
            if sig > 1.0:
                t0, t1 = float(time_s[i0]), float(time_s[i1 - 1])
                if spans and t0 - spans[-1][1] <= 1.5 * dt:
                    spans[-1][1] = t1
                    spans[-1][2] = max(spans[-1][2], sig)
                else:
                    spans.append([t0, t1, sig])
        self.spans_ = [[round(a0, 3), round(b0, 3), round(s0, 2)] for a0, b0, s0 in spans]
        return self
