"""Identified contours -> the chain model's shape table (robowrangler_sim.shape_table format).

One contour per (rope speed, phi), each dense (1 mm) in the table frame from the exit to the return
point. Every speed must have the same angles (check_photo_set). The points per contour are placed by
resample.py; with "curvature" the whole table shares one placement (resample.common_placement), so that
the spline over phi joins tip to tip and flank to flank.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from robowrangler_sim.identify.resample import common_placement, place_by_fractions, place_points
from robowrangler_sim.shape_table import ShapeTable

DENSE_SPACING_M = 1.0e-3


def build_table(contours: dict, *, n_points: int, placement: str, loop_length_m: float, source: str) -> ShapeTable:
    """Build the table.

    Args:
        contours: {rope_speed_mps: {phi_deg: dense contour (K, 2)}}, the same angles at every speed.
        n_points: points per contour in the table (>= 4).
        placement: "curvature" or "equal" (resample.py).
        loop_length_m: the loop length the contours were taken at (metres).
    """
    if n_points < 4:
        raise ValueError(f"n_points: expected >= 4, got {n_points}")
    speeds = sorted(contours)
    phis = sorted(contours[speeds[0]])
    if placement == "curvature":
        common = common_placement([contours[v][p] for v in speeds for p in phis], n_points,
                                  spacing_m=DENSE_SPACING_M)
        table = np.array([[place_by_fractions(contours[v][p], common) for p in phis] for v in speeds])
    else:
        table = np.array([[place_points(contours[v][p], n_points, placement=placement) for p in phis]
                          for v in speeds])
    return ShapeTable(phi_deg=np.array(phis, float), rope_speed_mps=np.array(speeds, float), contours_m=table,
                      loop_length_m=float(loop_length_m), source=source)


def save_table_atomically(table: ShapeTable, path: str | Path) -> Path:
    """Write the table to a temporary file beside ``path`` and rename it: ``path`` is whole or untouched."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".partial", dir=path.parent)
    os.close(fd)
    try:
        table.save(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
