"""Which rope pixels are the loop: the one thin, long, closed component that touches the exit point.

Closed means: it leaves the exit region and comes back to it (the module hides the last centimetres
of both branches, so "closed" is "two ends near the exit", checked when the centre line is ordered).
Other thin components (cables, edges of the clutter, fibres) do not reach the exit or are too short.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from robowrangler_sim.identify.centreline import BandEnds, band_ends
from robowrangler_sim.identify.errors import NoLoopFound, SeveralLoops


@dataclass(frozen=True)
class LoopComponent:
    """The loop's pixels in a crop of the image.

    Attributes:
        mask: shape (h, w) bool, the component in the crop.
        origin_px: (u0, v0), the crop's top-left in the image.
        length_px: estimated length along the rope (pixels).
        width_px: estimated mean width (pixels).
        band: the band cut free of the exit, with its two ends (crop coordinates).
    """

    mask: np.ndarray
    origin_px: tuple[int, int]
    length_px: float
    width_px: float
    band: BandEnds


def find_loop(mask: np.ndarray, exit_px, *, touch_radius_px: float, min_length_px: float, max_width_px: float,
              rope_width_px: float, path=None) -> LoopComponent:
    """The loop component of a binary mask (see module doc).

    Args:
        mask: shape (H, W) uint8 {0, 1}.
        exit_px: (u, v) of the guide exit.
        touch_radius_px: a component touches the exit when a pixel lies this close to it.
        min_length_px: shortest rope a loop can have in this photo.
        max_width_px: widest a rope can look.
        rope_width_px: the rope's apparent width (sets the steps of the exit cut).
    Raises NoLoopFound / SeveralLoops naming ``path``.
    """
    h, w = mask.shape
    u, v = float(exit_px[0]), float(exit_px[1])
    if not (0 <= u < w and 0 <= v < h):
        raise NoLoopFound(path, f"exit point ({u:.0f}, {v:.0f}) px lies outside the {w} x {h} image")
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    r = int(np.ceil(touch_radius_px))
    u0, v0, u1, v1 = max(int(u) - r, 0), max(int(v) - r, 0), min(int(u) + r + 1, w), min(int(v) + r + 1, h)
    yy, xx = np.mgrid[v0:v1, u0:u1]
    disc = (xx - u) ** 2 + (yy - v) ** 2 <= touch_radius_px ** 2
    touching = [int(i) for i in np.unique(labels[v0:v1, u0:u1][disc]) if i != 0]
    loops, rejected, open_ends = [], [], []
    for i in touching:
        x, y, bw, bh, area = (int(s) for s in stats[i])
        comp = (labels[y:y + bh, x:x + bw] == i).astype(np.uint8)
        contours, _ = cv2.findContours(comp, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        perimeter = sum(cv2.arcLength(c, True) for c in contours)
        length = 0.5 * perimeter       # a thin band: its outline runs along both sides
        width = area / max(length, 1.0)
        if length >= min_length_px and width <= max_width_px:
            band = band_ends(comp.astype(bool), (v - y, u - x), rope_width_px=rope_width_px,
                             max_cut_px=max(3.0 * touch_radius_px, 0.1 * length))
            if not isinstance(band, int):
                loops.append(LoopComponent(mask=comp.astype(bool), origin_px=(x, y), length_px=length,
                                           width_px=width, band=band))
                continue
            if band >= 4:
                raise SeveralLoops(path, f"{band // 2} loops share the exit point ({u:.0f}, {v:.0f}) px: the rope "
                                         f"component there has {band} ends; expected one loop (two ends)")
            open_ends.append(length)
        rejected.append((length, width))
    if not loops:
        detail = (f"; {len(rejected)} component(s) touch it but are too short, too wide or not closed (length, "
                  "width px: " + ", ".join(f"{a:.0f}, {b:.1f}" for a, b in rejected[:3]) + ")") if rejected else ""
        if open_ends:
            detail += f"; {len(open_ends)} of them do not come back to the exit (an open rope, not a loop)"
        raise NoLoopFound(path, f"no rope loop touches the exit point ({u:.0f}, {v:.0f}) px within "
                                f"{touch_radius_px:.0f} px (expected a thin component at least {min_length_px:.0f} px "
                                f"long){detail}")
    if len(loops) > 1:
        where = ", ".join(f"near ({c.origin_px[0]}, {c.origin_px[1]}) px, {c.length_px:.0f} px long" for c in loops)
        raise SeveralLoops(path, f"{len(loops)} candidate loops touch the exit point: {where}; expected one")
    return loops[0]
