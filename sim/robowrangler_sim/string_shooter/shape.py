"""Loop shape measures on a contour in the loop frame (shape (M, 2), x along the launch heading, z up)."""

from __future__ import annotations

import numpy as np


def roundness(points_xz_m: np.ndarray) -> float:
    """Isoperimetric quotient 4 pi A / P^2 of the contour closed through the eyelet: 1 for a circle,
    toward 0 for a hairpin."""
    xz = np.asarray(points_xz_m, dtype=float)
    x, z = xz[:, 0], xz[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(z, -1)) - np.dot(z, np.roll(x, -1)))
    perim = float(np.sum(np.linalg.norm(np.diff(np.vstack([xz, xz[:1]]), axis=0), axis=1)))
    return float(4 * np.pi * area / perim ** 2)


def reach_m(points_xz_m: np.ndarray) -> float:
    """Farthest distance of the contour from the exit point, metres."""
    xz = np.asarray(points_xz_m, dtype=float)
    return float(np.max(np.linalg.norm(xz - xz[0], axis=1)))
