"""Distance from a true centre line to a model's curve (the paper's Fig. 5a measure), per contour."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from robowrangler_sim.identify.centreline import resample_polyline


def curve_distances_m(points_m: np.ndarray, polyline_m: np.ndarray, *, resolution_m: float = 2.0e-4) -> np.ndarray:
    """Distance (K,) of each point (K, 2) to a polyline (M, 2), to within ``resolution_m`` / 2 or better.

    The polyline is densified to ``resolution_m`` and searched with a k-d tree (memory O(K + M), not K x M).
    """
    dense = resample_polyline(np.asarray(polyline_m, float), resolution_m)
    dist, _ = cKDTree(dense).query(np.asarray(points_m, float))
    return dist


def deviation_m(truth_m: np.ndarray, model_m: np.ndarray) -> tuple[float, float]:
    """(max, mean) distance from the true centre line (dense points) to the model's curve (polyline)."""
    d = curve_distances_m(truth_m, model_m)
    return float(d.max()), float(d.mean())
