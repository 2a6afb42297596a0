"""The centre line of the thick, fuzzy rope band, ordered from one end at the exit to the other.

The module hides the rope where it leaves and re-enters the guide, and near the exit the two branches
run close together. So the band is cut by a disc around the exit just large enough that what is left
is one band with two ends on the disc's rim (if it never has two, the rope does not come back: not a
loop). From one end, the geodesic distance inside the band (Dijkstra on the pixel graph, 8-neighbour)
orders every pixel along the rope; its level sets are the band's cross-sections, so the response-weighted
centroid of each one-pixel level set is a centre-line point. That is the "two-sided contour reduced to
its centre line" without a skeleton's spurs. A last pass moves each point to the centroid of the
response across the rope (profiles along the normal), which is sub-pixel and symmetric in the fuzz.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

_OFFSETS = ((0, 1, 1.0), (1, 0, 1.0), (1, 1, np.sqrt(2.0)), (1, -1, np.sqrt(2.0)))


def _graph(rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]):
    """8-neighbour pixel graph (CSR, symmetric weights 1 / sqrt 2) of the given pixels.

    Neighbours are looked up by binary search in the sorted linear pixel indices: memory and time follow
    the number of pixels, not the area of the crop they lie in.
    """
    h, w = shape
    key = rows.astype(np.int64) * (w + 2) + cols.astype(np.int64)
    order = np.argsort(key)
    sorted_key = key[order]
    src, dst, wts = [], [], []
    for dr, dc, wt in _OFFSETS:
        target = key + dr * (w + 2) + dc
        pos = np.clip(np.searchsorted(sorted_key, target), 0, key.size - 1)
        has = sorted_key[pos] == target
        src.append(np.nonzero(has)[0])
        dst.append(order[pos[has]])
        wts.append(np.full(int(has.sum()), wt))
    s, d, wv = np.concatenate(src), np.concatenate(dst), np.concatenate(wts)
    n = rows.size
    return coo_matrix((np.concatenate([wv, wv]), (np.concatenate([s, d]), np.concatenate([d, s]))),
                      shape=(n, n)).tocsr()


@dataclass(frozen=True)
class BandEnds:
    """The band with the exit disc cut out, and its two ends.

    Attributes:
        rows, cols: the band's pixels (crop coordinates) after the cut.
        graph: their 8-neighbour graph.
        ends: two index arrays into rows/cols, the pixels of each end (on the disc's rim).
        cut_radius_px: radius of the disc removed around the exit.
    """

    rows: np.ndarray
    cols: np.ndarray
    graph: object
    ends: tuple[np.ndarray, np.ndarray]
    cut_radius_px: float


def band_ends(mask: np.ndarray, exit_rc: tuple[float, float], *, rope_width_px: float,
              max_cut_px: float) -> BandEnds | int:
    """Cut discs of growing radius around the exit until one band with two rim ends remains.

    Returns the BandEnds, or (when no cut leaves exactly two ends) the largest number of ends seen: 1 or 0
    is an open rope, 4 or more is several loops sharing the exit.

    Args:
        mask: shape (h, w) bool, one connected component.
        exit_rc: the exit in the mask's (row, col) coordinates (may lie outside the crop).
        max_cut_px: give up beyond this radius.
    """
    rows_all, cols_all = np.nonzero(mask)
    dist = np.hypot(rows_all - exit_rc[0], cols_all - exit_rc[1])
    step = max(1.5 * rope_width_px, 2.0)
    cut = float(dist.min()) + step
    most = 0
    while cut <= max_cut_px:
        keep = dist > cut
        rows, cols, d = rows_all[keep], cols_all[keep], dist[keep]
        if rows.size < 10:
            return most
        graph = _graph(rows, cols, mask.shape)
        n_comp, labels = connected_components(graph, directed=False)
        main = np.argmax(np.bincount(labels))
        in_main = labels == main
        rim = np.nonzero(in_main & (d <= cut + step))[0]
        if rim.size:
            sub = graph[rim][:, rim]
            n_rim, rim_labels = connected_components(sub, directed=False)
            sizes = np.bincount(rim_labels)
            big = [k for k in range(n_rim) if sizes[k] >= max(2, 0.3 * rope_width_px)]
            most = max(most, len(big))
            if len(big) == 2:
                sel = np.nonzero(in_main)[0]
                remap = np.full(rows.size, -1, np.int64)
                remap[sel] = np.arange(sel.size)
                ends = tuple(remap[rim[rim_labels == k]] for k in big)
                return BandEnds(rows=rows[sel], cols=cols[sel], graph=graph[sel][:, sel], ends=ends,
                                cut_radius_px=cut)
        cut += step
    return most


def ordered_centre_line(band: BandEnds, weights: np.ndarray, *, bin_px: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Centre-line points (K, 2) as (col, row) in crop coordinates, from ``band.ends[0]`` to ``band.ends[1]``,
    and the spread (K,) of each level set: its largest distance from its centroid, pixels.

    A level set wider than a few rope widths means the band forks (two ropes side by side or crossing).

    Args:
        weights: shape of the crop, the response (how much each pixel is rope).
    """
    geo = dijkstra(band.graph, directed=False, indices=band.ends[0], min_only=True)
    finite = np.isfinite(geo)
    bins = np.floor(geo[finite] / bin_px).astype(np.int64)
    rows, cols = band.rows[finite].astype(np.float64), band.cols[finite].astype(np.float64)
    w = np.maximum(weights[band.rows[finite], band.cols[finite]].astype(np.float64), 1e-6)
    total = np.bincount(bins, weights=w)
    ok = total > 0
    cx = np.bincount(bins, weights=w * cols) / np.where(ok, total, 1.0)
    cy = np.bincount(bins, weights=w * rows) / np.where(ok, total, 1.0)
    spread = np.zeros(total.size)
    np.maximum.at(spread, bins, np.hypot(cols - cx[bins], rows - cy[bins]))
    return np.column_stack([cx[ok], cy[ok]]), spread[ok]


def resample_polyline(points: np.ndarray, spacing: float) -> np.ndarray:
    """Points (K, 2) resampled every ``spacing`` along the polyline (ends kept)."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(int(np.ceil(s[-1] / spacing)) + 1, 2)
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, points[:, 0]), np.interp(t, s, points[:, 1])])


def refine_centre_line(points_px: np.ndarray, response: np.ndarray, *, half_width_px: float,
                       smooth_px: float = 2.0, iterations: int = 2) -> np.ndarray:
    """Move each point to the response centroid across the rope; returns (K, 2) image (u, v), 1 px spacing."""
    pts = resample_polyline(points_px, 1.0)
    offsets = np.arange(-half_width_px, half_width_px + 1e-9, 0.5, dtype=np.float64)
    for _ in range(iterations):
        pts = gaussian_filter1d(pts, smooth_px, axis=0, mode="nearest")
        tangent = np.gradient(pts, axis=0)
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-9)
        normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
        sample = pts[:, None, :] + offsets[None, :, None] * normal[:, None, :]
        prof = cv2.remap(response, sample[..., 0].astype(np.float32), sample[..., 1].astype(np.float32),
                         cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0).astype(np.float64)
        prof = np.maximum(prof - 0.3 * prof.max(axis=1, keepdims=True), 0.0)
        total = prof.sum(axis=1)
        shift = np.where(total > 0, (prof * offsets[None, :]).sum(axis=1) / np.maximum(total, 1e-12), 0.0)
        shift = np.clip(shift, -0.5 * half_width_px, 0.5 * half_width_px)
        pts = pts + shift[:, None] * normal
        pts = resample_polyline(pts, 1.0)
    return gaussian_filter1d(pts, smooth_px, axis=0, mode="nearest")


def trim_ends(points: np.ndarray, length: float) -> np.ndarray:
    """The polyline (K, 2) without ``length`` of arc at each end (unchanged if it is not 4 x longer)."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    if s[-1] <= 4.0 * length:
        return points
    keep = (s >= length) & (s <= s[-1] - length)
    return points[keep]
