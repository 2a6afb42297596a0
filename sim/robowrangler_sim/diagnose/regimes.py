"""Regime labels per telemetry sample: speed band and motion (accelerating / steady / decelerating)."""

from __future__ import annotations

import numpy as np

SPEED_BANDS_MPS = ((0.0, 0.3, "rest"), (0.3, 2.0, "0.3-2 m/s"), (2.0, 5.0, "2-5 m/s"), (5.0, 8.0, "5-8 m/s"),
                   (8.0, np.inf, "> 8 m/s"))
ACCEL_MPS2 = 1.0  # |dv/dt| above this is a transient


def speed_band(speed_mps: np.ndarray) -> np.ndarray:
    out = np.empty(speed_mps.shape, dtype=object)
    for lo, hi, name in SPEED_BANDS_MPS:
        out[(speed_mps >= lo) & (speed_mps < hi)] = name
    return out


def motion(t_s: np.ndarray, speed_mps: np.ndarray) -> np.ndarray:
    dv = np.gradient(speed_mps, t_s)
    out = np.full(speed_mps.shape, "steady", dtype=object)
    out[dv > ACCEL_MPS2] = "accelerating"
    out[dv < -ACCEL_MPS2] = "decelerating"
    return out


def regime_labels(t_s: np.ndarray, speed_mps: np.ndarray) -> dict[str, np.ndarray]:
    """{"speed_band": (S,), "motion": (S,)} label arrays."""
    return {"speed_band": speed_band(speed_mps), "motion": motion(t_s, speed_mps)}


def dominant_regime(labels: dict[str, np.ndarray], mask: np.ndarray) -> dict[str, object]:
    """The labels covering a mask: each kind -> {label: share of the masked samples} (shares >= 5 %)."""
    out: dict[str, object] = {}
    n = int(mask.sum())
    for kind, lab in labels.items():
        if n == 0:
            out[kind] = {}
            continue
        vals, counts = np.unique(lab[mask].astype(str), return_counts=True)
        out[kind] = {str(v): round(float(c) / n, 3) for v, c in zip(vals, counts) if c / n >= 0.05}
    return out


def coverage(labels: dict[str, np.ndarray]) -> dict[str, list[str]]:
    """Which regimes the recording visited (>= 1 % of samples) and which it never did."""
    visited, missing = [], []
    all_labels = {"speed_band": [b[2] for b in SPEED_BANDS_MPS], "motion": ["accelerating", "steady", "decelerating"]}
    for kind, names in all_labels.items():
        lab = labels[kind].astype(str)
        for name in names:
            (visited if np.mean(lab == name) >= 0.01 else missing).append(f"{kind}:{name}")
    return {"visited": visited, "not_visited": missing}
