"""One photo -> the loop's dense contour in the table frame (metres, exit first, return point last).

read -> calibrate -> response + binarise -> the loop component -> ordered centre line -> refine ->
pixels to plane metres -> table frame. The table frame (shape_table.py): origin at the exit, x
horizontal away from the robot, z up. The calibration's plane frame already has Y up; "away from the
robot" is the side the loop lies on; the branch order is fixed by the loop's turning sense (out along
the upper branch and back along the lower one is clockwise in x-right, z-up coordinates).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robowrangler_sim.identify.binarise import binarise, rope_response
from robowrangler_sim.identify.calibration import PlaneCalibration, calibration_for_photo
from robowrangler_sim.identify.centreline import (ordered_centre_line, refine_centre_line, resample_polyline,
                                                  trim_ends)
from robowrangler_sim.identify.errors import CalibrationError, ManifestError, NoLoopFound, SeveralLoops
from robowrangler_sim.identify.gaps import bridge_gaps
from robowrangler_sim.identify.loop_finder import find_loop
from robowrangler_sim.identify.photos import PhotoEntry, read_gray


FORK_SPREAD_ROPE_WIDTHS = 4.0  # a cross-section of the band wider than this is two ropes
FORK_FRACTION = 0.05           # ... along more than this share of the loop: several loops


@dataclass(frozen=True)
class ExtractOptions:
    """How photos are read.

    Attributes:
        rope_polarity: "bright" (light rope on a darker background) or "dark".
        rope_width_m: apparent rope width with its fuzz, metres (sets the filter sizes).
        touch_radius_m: the loop must come this close to the exit point (the module hides the rest).
        max_rope_width_m: wider components are not rope.
        min_loop_length_m: shorter components are not the loop.
        max_gap_m: longest gap in the rope bridged when the loop is found only in pieces (gaps.py); 0: never.
        end_trim_m: rope dropped at each end of the visible band before joining it to the exit and the
            return point with straight lines (near the module, its edges and the converging branches
            disturb the band; the rope there runs straight).
        dense_spacing_m: spacing of the returned contour.
    """

    rope_polarity: str = "bright"
    rope_width_m: float = 4.0e-3
    touch_radius_m: float = 0.08
    max_rope_width_m: float = 0.02
    min_loop_length_m: float = 0.3
    end_trim_m: float = 0.02
    max_gap_m: float = 0.2
    dense_spacing_m: float = 1.0e-3


@dataclass(frozen=True)
class PhotoResult:
    """What one photo gave.

    Attributes:
        entry: the photo.
        calibration: its pixels-to-plane homography.
        centre_line_px: shape (K, 2), the extracted centre line in the image, exit side of the upper branch first.
        contour_m: shape (M, 2), dense contour in the table frame (exit, centre line, return point).
        loop_length_m: the contour's arc length.
        exit_plane_m: shape (2,), the exit in the calibration's plane frame; sense: +1 if the table's x is
            the plane's X, -1 if mirrored (robot on the right).
        gaps_bridged: gaps in the rope bridged to close the loop (gaps.py).
    """

    entry: PhotoEntry
    calibration: PlaneCalibration
    centre_line_px: np.ndarray
    contour_m: np.ndarray
    loop_length_m: float
    exit_plane_m: np.ndarray
    sense: float
    gaps_bridged: int = 0

    def table_to_image(self, points_m: np.ndarray) -> np.ndarray:
        """Table-frame points (K, 2) -> image pixels (K, 2) of this photo."""
        pts = np.asarray(points_m, float)
        plane = np.column_stack([self.sense * pts[:, 0], pts[:, 1]]) + self.exit_plane_m
        return self.calibration.to_image(plane)


def _signed_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def extract_photo(entry: PhotoEntry, calibration_spec: dict, *, options: ExtractOptions | None = None,
                  calibration: PlaneCalibration | None = None) -> PhotoResult:
    """Identify the loop in one photo (see module doc). Errors are IdentifyError subclasses naming the file."""
    opt = options or ExtractOptions()
    path = entry.path
    gray = read_gray(path)
    if entry.exit_px is None:
        raise ManifestError(path, "exit_px missing: expected the guide exit's pixel position (manifest exit_px or --exit-px)")
    cal = calibration or calibration_for_photo(calibration_spec, gray, path=path)
    h, w = gray.shape
    u, v = entry.exit_px
    if not (0 <= u < w and 0 <= v < h):
        raise ManifestError(path, f"exit_px ({u:g}, {v:g}): expected inside the {w} x {h} image")
    mpp = cal.metres_per_px(entry.exit_px)
    if not (np.isfinite(mpp) and 1e-5 < mpp < 0.05):
        raise CalibrationError(path, f"calibration gives {mpp * 1e3:.3g} mm per pixel at the exit; expected "
                                     "0.01..50 mm (wrong marker size or intrinsics?)")
    rope_px = max(opt.rope_width_m / mpp, 2.0)
    response = rope_response(gray, rope_width_px=rope_px, polarity=opt.rope_polarity)
    mask = binarise(response)
    find = dict(touch_radius_px=opt.touch_radius_m / mpp, min_length_px=opt.min_loop_length_m / mpp,
                max_width_px=opt.max_rope_width_m / mpp, rope_width_px=rope_px, path=path)
    bridges = 0
    try:
        loop = find_loop(mask, entry.exit_px, **find)
    except NoLoopFound:
        if opt.max_gap_m <= 0:
            raise
        mask, bridges = bridge_gaps(mask, rope_width_px=rope_px, max_gap_px=opt.max_gap_m / mpp,
                                    min_piece_px=0.03 / mpp, max_width_px=opt.max_rope_width_m / mpp)
        if bridges == 0:
            raise
        loop = find_loop(mask, entry.exit_px, **find)
    u0, v0 = loop.origin_px
    hh, ww = loop.mask.shape
    coarse, spread = ordered_centre_line(loop.band, response[v0:v0 + hh, u0:u0 + ww])
    coarse += np.array([u0, v0], float)
    forked = float(np.mean(spread > FORK_SPREAD_ROPE_WIDTHS * max(rope_px, loop.width_px)))
    if forked > FORK_FRACTION:
        raise SeveralLoops(path, f"the rope forks along {100 * forked:.0f} % of the loop (ropes side by side or "
                                 "crossing): several loops, or another rope, touch the exit; expected one loop")
    coarse = trim_ends(coarse, opt.end_trim_m / mpp)
    line_px = refine_centre_line(coarse, response, half_width_px=max(3.0, 1.5 * rope_px))
    plane = cal.to_plane(line_px)
    exit_plane = cal.to_plane(np.array([entry.exit_px]))[0]
    ret_plane = cal.to_plane(np.array([entry.return_px if entry.return_px is not None else entry.exit_px]))[0]
    sense = 1.0 if float(np.mean(plane[:, 0])) >= exit_plane[0] else -1.0

    def to_table(p):
        q = np.asarray(p, float) - exit_plane
        return np.column_stack([sense * q[..., 0], q[..., 1]]) if q.ndim == 2 else np.array([sense * q[0], q[1]])

    curve = to_table(plane)
    ret = to_table(ret_plane)
    poly = np.vstack([[0.0, 0.0], curve, ret])
    if _signed_area(poly) > 0:  # counter-clockwise: it was ordered from the lower branch
        curve = curve[::-1]
        line_px = line_px[::-1]
        poly = np.vstack([[0.0, 0.0], curve, ret])
    dense = resample_polyline(poly, opt.dense_spacing_m)
    length = float(np.sum(np.linalg.norm(np.diff(dense, axis=0), axis=1)))
    return PhotoResult(entry=entry, calibration=cal, centre_line_px=line_px, contour_m=dense, loop_length_m=length,
                       exit_plane_m=exit_plane, sense=sense, gaps_bridged=bridges)
