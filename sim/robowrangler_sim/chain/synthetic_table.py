"""A synthetic, purely geometric shape table: an ellipse-like loop, longer and flatter at negative phi.

Not physics. It exists so that tests and benchmarks of the chain model have a well-defined target
when no identified or simulated table is at hand. The default table the product ships is
``robowrangler_sim/data/shape_table_default.json`` (see default_table.py).

Construction per phi (table frame, see shape_table.py): in a frame rotated by the loop axis angle
beta = phi - droop_deg, the curve p(t) = (a (1 - cos t), b sin t - gap t / (2 pi)), t in [0, 2 pi],
starts at the exit, runs along the upper branch (positive side) round the tip (t = pi) and back along
the lower branch to the return point ``gap`` below the exit; it is scaled to the loop length and
resampled to equally spaced points.
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.shape_table import ShapeTable, resample_by_arc_length


def synthetic_ellipse_table(*, loop_length_m: float = 2.0, n_points: int = 41,
                            phi_deg: np.ndarray | None = None, droop_deg: float = 8.0,
                            aspect_at_min_phi: float = 0.22, aspect_at_max_phi: float = 0.42,
                            return_gap_m: float = 0.03, rope_speed_mps: float = 5.0) -> ShapeTable:
    """Build the synthetic table.

    Args:
        loop_length_m: arc length of every contour, metres.
        n_points: points per contour.
        phi_deg: shape (P,), inclinations; default -30..40 deg in 5 deg steps (the paper's grid).
        droop_deg: loop axis below the launch axis, degrees.
        aspect_at_min_phi, aspect_at_max_phi: minor/major axis ratio at the first and last phi.
        return_gap_m: return point below the exit (before scaling to loop_length_m), metres.
        rope_speed_mps: the one speed the table is tagged with.
    Returns: a ShapeTable with one speed.
    """
    phis = np.arange(-30.0, 40.0 + 1e-9, 5.0) if phi_deg is None else np.asarray(phi_deg, dtype=float)
    t = np.linspace(0.0, 2.0 * np.pi, 400)
    contours = []
    for phi in phis:
        w = (phi - phis[0]) / max(phis[-1] - phis[0], 1e-9)
        aspect = aspect_at_min_phi + w * (aspect_at_max_phi - aspect_at_min_phi)
        a, b = 1.0, aspect
        u = a * (1.0 - np.cos(t))
        v = b * np.sin(t) - return_gap_m * t / (2.0 * np.pi)
        beta = np.deg2rad(phi - droop_deg)
        pts = np.column_stack([u * np.cos(beta) - v * np.sin(beta), u * np.sin(beta) + v * np.cos(beta)])
        arc = float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)))
        contours.append(resample_by_arc_length(pts * (loop_length_m / arc), n_points))
    return ShapeTable(phi_deg=phis, rope_speed_mps=np.array([rope_speed_mps]),
                      contours_m=np.array([contours]), loop_length_m=loop_length_m,
                      source="synthetic ellipse-like loop (robowrangler_sim.chain.synthetic_table); "
                             "geometry only, not physics")
