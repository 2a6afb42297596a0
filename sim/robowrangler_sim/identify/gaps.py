"""Bridging gaps in the rope: where a light rope crosses a light object it can vanish for a few
centimetres, and the loop falls apart into open pieces. Each thin piece's two ends (the extremes of the
geodesic distance inside it) and the rope's direction there are found; two ends of different pieces that
face each other across a gap no longer than ``max_gap_px`` (both directions within ~35 deg of the gap)
are joined by a straight band of the rope's width, closest pairs first, each end at most once. Used only
when no closed loop is found without it; the straight bridge over a gently curved branch is off by
gap^2 / (8 R), about 2 mm for a 13 cm gap on a 1 m radius.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.sparse.csgraph import dijkstra

from robowrangler_sim.identify.centreline import _graph

MIN_ALIGNMENT = 0.82  # cos of the largest angle between an end's direction and the gap


def _piece_ends(comp: np.ndarray, *, back_px: float):
    """The two ends of a thin piece (crop coords, (row, col)) and the outward direction at each."""
    rows, cols = np.nonzero(comp)
    graph = _graph(rows, cols, comp.shape)
    d0 = dijkstra(graph, directed=False, indices=0)
    a = int(np.argmax(np.where(np.isfinite(d0), d0, -1)))
    da = dijkstra(graph, directed=False, indices=a)
    b = int(np.argmax(np.where(np.isfinite(da), da, -1)))
    db = dijkstra(graph, directed=False, indices=b)
    ends = []
    for idx, dist in ((a, da), (b, db)):
        near = np.isfinite(dist) & (dist > back_px) & (dist < 2 * back_px)
        if not near.any():
            return []
        p = np.array([rows[idx], cols[idx]], float)
        q = np.array([rows[near].mean(), cols[near].mean()])
        direction = p - q
        n = np.linalg.norm(direction)
        if n == 0:
            return []
        ends.append((p, direction / n))
    return ends


def bridge_gaps(mask: np.ndarray, *, rope_width_px: float, max_gap_px: float, min_piece_px: float,
                max_width_px: float) -> tuple[np.ndarray, int]:
    """The mask with gaps between facing rope ends bridged (see module doc); returns (mask, bridges drawn)."""
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    ends = []  # (piece, point (row, col) in the image, direction)
    back = max(4.0 * rope_width_px, 8.0)
    for i in range(1, n):
        x, y, w, h, area = (int(s) for s in stats[i])
        if max(w, h) < min_piece_px or area > max_width_px * 4 * max(w, h):
            continue
        comp = labels[y:y + h, x:x + w] == i
        for p, d in _piece_ends(comp, back_px=back):
            ends.append((i, p + np.array([y, x], float), d))
    pairs = []
    for a in range(len(ends)):
        for b in range(a + 1, len(ends)):
            ia, pa, da = ends[a]
            ib, pb, db = ends[b]
            if ia == ib:
                continue
            gap = pb - pa
            dist = float(np.linalg.norm(gap))
            if dist == 0 or dist > max_gap_px:
                continue
            g = gap / dist
            if np.dot(da, g) >= MIN_ALIGNMENT and np.dot(db, -g) >= MIN_ALIGNMENT:
                pairs.append((dist, a, b))
    out = mask.copy()
    used: set[int] = set()
    drawn = 0
    for dist, a, b in sorted(pairs):
        if a in used or b in used:
            continue
        used.update((a, b))
        pa, pb = ends[a][1], ends[b][1]
        cv2.line(out, (int(round(pa[1])), int(round(pa[0]))), (int(round(pb[1])), int(round(pb[0]))), 1,
                 max(int(round(rope_width_px)), 1), cv2.LINE_8)
        drawn += 1
    return out, drawn
