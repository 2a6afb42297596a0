"""Shape identification, the Python API: photos -> the chain model's shape table (+ a figure per photo).

    from robowrangler_sim.identify import identify_manifest, write_identification
    result = identify_manifest("photos/manifest.json")          # IdentifyResult
    write_identification(result, "my_table.json", figures_dir="figures/")
    ChainPlant(table=result.table, ...)                           # or ShapeTable.load("my_table.json")

All photos are processed (in parallel threads: OpenCV releases the GIL) before anything is written; one
bad photo stops the whole identification with an error naming it, and no table is written.
"""

from __future__ import annotations

import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robowrangler_sim.identify.errors import CalibrationError
from robowrangler_sim.identify.extract import ExtractOptions, PhotoResult, extract_photo
from robowrangler_sim.identify.photos import PhotoEntry, PhotoSet, check_photo_set, load_manifest
from robowrangler_sim.identify.resample import PLACEMENTS
from robowrangler_sim.identify.table_builder import build_table, save_table_atomically
from robowrangler_sim.shape_table import ShapeTable

LENGTH_TOLERANCE = 0.08  # a photo whose loop length differs more than this from the others' median is misfit


@dataclass(frozen=True)
class IdentifyResult:
    """The identified table and what each photo gave.

    Attributes:
        table: the shape table (the format of robowrangler_sim.shape_table).
        photos: one PhotoResult per photo, in the table's order (speed, then phi).
        elapsed_s: wall time of the identification (reading, extraction, table).
    """

    table: ShapeTable
    photos: tuple[PhotoResult, ...]
    elapsed_s: float


def identify(photo_set: PhotoSet, *, n_points: int = 41, placement: str = "curvature",
             options: ExtractOptions | None = None, workers: int | None = None) -> IdentifyResult:
    """Identify the shape table from a photo set.

    Args:
        photo_set: the photos, their phi / speed / exit point, the calibration spec, the expected loop length.
        n_points: points per contour in the table.
        placement: "curvature" (tip-anchored, curvature-aware; default) or "equal" (the paper's equal chords).
        workers: threads (default: the machine's cores, at most 4).
    Raises IdentifyError subclasses naming the file at fault.
    """
    if placement not in PLACEMENTS:
        raise ValueError(f"placement: expected one of {PLACEMENTS}, got {placement!r}")
    if n_points < 4:
        raise ValueError(f"n_points: expected >= 4, got {n_points}")
    t0 = time.perf_counter()
    groups = check_photo_set(photo_set.photos)
    ordered = [p for speed in groups for p in groups[speed]]
    n_workers = workers or min(os.cpu_count() or 1, 4)
    opt = options or ExtractOptions()

    def run(entry: PhotoEntry) -> PhotoResult:
        return extract_photo(entry, photo_set.calibration, options=opt)

    if n_workers > 1 and len(ordered) > 1:
        with ThreadPoolExecutor(max_workers=n_workers) as pool:
            results = list(pool.map(run, ordered))
    else:
        results = [run(e) for e in ordered]
    lengths = np.array([r.loop_length_m for r in results])
    reference = photo_set.loop_length_m if photo_set.loop_length_m is not None else float(np.median(lengths))
    for r in results:
        if abs(r.loop_length_m / reference - 1.0) > LENGTH_TOLERANCE:
            what = "the manifest's loop_length_m" if photo_set.loop_length_m is not None else "the other photos' median"
            raise CalibrationError(r.entry.path, f"calibration does not fit: the loop measures {r.loop_length_m:.3f} m, "
                                                 f"{what} is {reference:.3f} m (more than {100 * LENGTH_TOLERANCE:.0f} % "
                                                 "apart: wrong marker size, a moved camera, or not the loop)")
    contours: dict = {}
    for r in results:
        contours.setdefault(r.entry.rope_speed_mps, {})[r.entry.phi_deg] = r.contour_m
    calibrations = sorted({r.calibration.source for r in results})
    source = (f"wrangler identify: {len(results)} photos, calibration {'; '.join(calibrations)}, "
              f"{placement} placement of {n_points} points, contours measured at loop length "
              f"{float(np.median(lengths)):.3f} m (median)")
    table = build_table(contours, n_points=n_points, placement=placement,
                        loop_length_m=float(np.median(lengths)), source=source)
    return IdentifyResult(table=table, photos=tuple(results), elapsed_s=time.perf_counter() - t0)


def identify_manifest(path: str | Path, **kwargs) -> IdentifyResult:
    """identify(load_manifest(path), **kwargs)."""
    return identify(load_manifest(path), **kwargs)


def write_identification(result: IdentifyResult, table_path: str | Path, *, figures_dir: str | Path | None = None) -> Path:
    """Write the table (atomically: whole or not at all) and, if asked, a PNG per photo. Returns the table path.

    The figures are written first: the table appears only once everything else has been written.
    """
    if figures_dir is not None:
        from robowrangler_sim.identify.figures import write_photo_figure

        out = Path(figures_dir)
        out.mkdir(parents=True, exist_ok=True)
        for r in result.photos:
            write_photo_figure(r, result.table, out / f"{r.entry.path.stem}_identified.png")
    return save_table_atomically(result.table, table_path)
