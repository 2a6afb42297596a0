"""N points on an identified contour: the paper's equal chords, or tip-anchored curvature-aware placement.

Equal chords (the paper): N points equally spaced in arc length. At a sharp tip the chord between two
of them cuts the corner by about c^2 / (8 r) (chord c, tip radius r), and the tip itself usually falls
between two points, so the model's loop is shorter than the real one there.

Curvature-aware (ours): the point density along the rope follows sqrt(curvature + kappa_floor) (the
density that equalises the chord error c^2 kappa / 8 of a piecewise-linear curve, with a floor so the
straight branches keep their share), and the tip (the point farthest from the exit) is always a point,
at the same index in every contour of a table. The consistency matters as much as the density: the
table is interpolated over phi point by point (ShapeTable.contour, a cubic spline through all angles),
so point k must be the same feature of the loop at every phi, or the interpolated tip is the blend of
two flanks and one odd contour rings through the spline to its neighbours. So a table has ONE
placement: fractions along each half of the loop (exit -> tip, tip -> return point) from the median
density profile over all its contours (common_placement).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from robowrangler_sim.shape_table import resample_by_arc_length

PLACEMENTS = ("curvature", "equal")
KAPPA_FLOOR_PER_M = 1.0
KAPPA_CAP_PER_M = 200.0


def arc_length_m(curve_m: np.ndarray) -> np.ndarray:
    """Cumulative arc length (K,) of a polyline (K, 2), from 0."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve_m, axis=0), axis=1))])


def tip_index(curve_m: np.ndarray) -> int:
    """Index of the point farthest from the exit (the first point)."""
    return int(np.argmax(np.linalg.norm(curve_m - curve_m[0], axis=1)))


def placement_density(curve_m: np.ndarray, *, spacing_m: float) -> np.ndarray:
    """sqrt(|curvature| + floor) per point of a curve sampled every ``spacing_m``.

    Curvature from a curve smoothed over 5 mm, capped at 1 / (5 mm) (a fibre's kink is not a tip), then
    smoothed over 2 cm along the rope.
    """
    smooth = gaussian_filter1d(curve_m, max(5.0e-3 / spacing_m, 1.0), axis=0, mode="nearest")
    d1 = np.gradient(smooth, spacing_m, axis=0)
    d2 = np.gradient(d1, spacing_m, axis=0)
    speed = np.maximum(np.linalg.norm(d1, axis=1), 1e-9)
    kappa = np.minimum(np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / speed ** 3, KAPPA_CAP_PER_M)
    kappa = gaussian_filter1d(kappa, max(0.02 / spacing_m, 1.0), mode="nearest")
    return np.sqrt(kappa + KAPPA_FLOOR_PER_M)


def _cumulative(density: np.ndarray, s: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(s))])


@dataclass(frozen=True)
class Placement:
    """Where N points go, as fractions of each half of the loop (exit -> tip, tip -> return point).

    Attributes:
        out_fractions: shape (k_tip + 1,), 0 .. 1 along exit -> tip (the tip is index k_tip).
        back_fractions: shape (N - k_tip,), 0 .. 1 along tip -> return point.
    """

    out_fractions: np.ndarray
    back_fractions: np.ndarray

    @property
    def n_points(self) -> int:
        return self.out_fractions.size + self.back_fractions.size - 1

    @property
    def tip_index(self) -> int:
        return self.out_fractions.size - 1


def common_placement(curves_m, n_points: int, *, spacing_m: float = 1.0e-3) -> Placement:
    """One placement for a set of contours (a table): the median density profile over the set, per half.

    Each contour's density is taken as a function of the fraction along its half (exit -> tip, tip ->
    return); the median over the contours (robust to one bad photo) sets the fractions, and the two
    halves share the N points in proportion to their integrated density.
    """
    grid = np.linspace(0.0, 1.0, 401)
    outs, backs, w_out, w_back = [], [], [], []
    for c in curves_m:
        s = arc_length_m(c)
        rho = placement_density(c, spacing_m=spacing_m)
        k = int(np.clip(tip_index(c), 1, len(c) - 2))
        s_tip, total = s[k], s[-1]
        outs.append(np.interp(grid * s_tip, s[:k + 1], rho[:k + 1]))
        backs.append(np.interp(s_tip + grid * (total - s_tip), s[k:], rho[k:]))
        w_out.append(s_tip)
        w_back.append(total - s_tip)
    rho_out, rho_back = np.median(outs, axis=0), np.median(backs, axis=0)
    cum_out = _cumulative(rho_out, grid) * float(np.median(w_out))
    cum_back = _cumulative(rho_back, grid) * float(np.median(w_back))
    k_tip = int(np.clip(round((n_points - 1) * cum_out[-1] / (cum_out[-1] + cum_back[-1])), 1, n_points - 2))
    out = np.interp(np.linspace(0.0, cum_out[-1], k_tip + 1), cum_out, grid)
    back = np.interp(np.linspace(0.0, cum_back[-1], n_points - k_tip), cum_back, grid)
    return Placement(out_fractions=out, back_fractions=back)


def place_by_fractions(curve_m: np.ndarray, placement: Placement) -> np.ndarray:
    """The points of a placement on one dense contour (K, 2): shape (N, 2), exit first, tip at tip_index."""
    s = arc_length_m(curve_m)
    k = int(np.clip(tip_index(curve_m), 1, len(curve_m) - 2))
    s_tip, total = s[k], s[-1]
    target = np.concatenate([placement.out_fractions * s_tip,
                             s_tip + placement.back_fractions[1:] * (total - s_tip)])
    return np.column_stack([np.interp(target, s, curve_m[:, 0]), np.interp(target, s, curve_m[:, 1])])


def place_points(curve_m: np.ndarray, n_points: int, *, placement: str, spacing_m: float = 1.0e-3) -> np.ndarray:
    """``n_points`` points on one dense curve (K, 2) sampled every ``spacing_m``; first and last kept.

    Args:
        placement: "equal" (equal arc length, the paper) or "curvature" (see module doc; for a whole
            table use common_placement so that every contour shares it).
    """
    if placement not in PLACEMENTS:
        raise ValueError(f"placement: expected one of {PLACEMENTS}, got {placement!r}")
    if placement == "equal":
        return resample_by_arc_length(curve_m, n_points)
    return place_by_fractions(curve_m, common_placement([curve_m], n_points, spacing_m=spacing_m))
