"""`wrangler identify PHOTOS... --out SHAPE_TABLE`: the loop's shape table from photos (issue 16).

A plugin of `wrangler` (robowrangler_sim.cli.commands). PHOTOS is a manifest (.json, see
robowrangler_sim/identify/photos.py) or image files whose names carry phi and the rope speed
(``loop_phi-30_v5.0.png``), with the geometry on the command line. The result line goes to stdout (one
JSON object with ``wrangler --json``), a line per photo to stderr. Errors (an unreadable photo, no
loop, several loops, phi missing or repeated, a calibration that does not fit) name the file, exit with
status 1 (ERROR), and no table is written.
"""

from __future__ import annotations

from pathlib import Path

import click

from robowrangler.cli.context import CliContext, pass_context


def _pixel(ctx, param, value):
    if value is None:
        return None
    try:
        u, v = (float(c) for c in value.split(","))
    except ValueError:
        raise click.BadParameter(f"expected U,V in pixels (e.g. 736.1,680.2), got {value!r}") from None
    return (u, v)


@click.command("identify")
@click.argument("photos", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "out_path", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Shape table to write (JSON, the chain model's format).")
@click.option("--figures", "figures_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Folder for one PNG per photo: the photo, the extracted centre line, the fitted chain.")
@click.option("--points", "n_points", type=click.IntRange(min=4), default=41, show_default=True,
              help="Points per contour in the table.")
@click.option("--placement", type=click.Choice(["curvature", "equal"]), default="curvature", show_default=True,
              help="curvature: tip-anchored, denser where the loop bends; equal: the paper's equal chords.")
@click.option("--marker-side-m", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Calibration: side of the ArUco marker hung level in the loop plane, metres.")
@click.option("--marker-id", type=click.IntRange(min=0), default=0, show_default=True)
@click.option("--marker-dictionary", default="DICT_4X4_50", show_default=True)
@click.option("--focal-px", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Calibration without a marker: focal length in pixels (with --distance-m).")
@click.option("--distance-m", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Camera to loop plane along the optical axis, metres.")
@click.option("--exit-px", callback=_pixel, default=None, metavar="U,V", help="The guide exit in the photos, pixels.")
@click.option("--return-px", callback=_pixel, default=None, metavar="U,V",
              help="Where the rope re-enters the module, pixels (default: the exit).")
@click.option("--rope-speed-mps", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Rope speed of every photo (when the file names do not say it).")
@click.option("--loop-length-m", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Expected loop length: a photo measuring more than 8 %% off is a calibration error.")
@click.option("--rope", "rope_polarity", type=click.Choice(["bright", "dark"]), default="bright", show_default=True,
              help="Rope lighter or darker than the background.")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Threads (default: cores, at most 4).")
@pass_context
def identify_command(ctx: CliContext, photos, out_path, figures_dir, n_points, placement, marker_side_m, marker_id,
                     marker_dictionary, focal_px, distance_m, exit_px, return_px, rope_speed_mps, loop_length_m,
                     rope_polarity, workers) -> None:
    """Identify the loop's shape table from PHOTOS (a manifest .json, or images named ..._phi-30_v5.0.png)."""
    from robowrangler_sim.identify import (ExtractOptions, PhotoEntry, PhotoSet, entry_from_name, identify,
                                           load_manifest, write_identification)

    if len(photos) == 1 and photos[0].suffix.lower() == ".json":
        photo_set = load_manifest(photos[0])
        calibration = dict(photo_set.calibration)
        entries = [PhotoEntry(path=e.path, phi_deg=e.phi_deg, rope_speed_mps=e.rope_speed_mps,
                              exit_px=exit_px or e.exit_px, return_px=return_px or e.return_px)
                   for e in photo_set.photos]
        loop_len = loop_length_m if loop_length_m is not None else photo_set.loop_length_m
    else:
        if any(p.suffix.lower() == ".json" for p in photos):
            raise click.UsageError("give either one manifest (.json) or image files, not both")
        entries = [entry_from_name(p, rope_speed_mps=rope_speed_mps, exit_px=exit_px, return_px=return_px)
                   for p in photos]
        calibration, loop_len = {}, loop_length_m
    if marker_side_m is not None:
        calibration = {"marker": {"side_m": marker_side_m, "id": marker_id, "dictionary": marker_dictionary}}
    elif focal_px is not None or distance_m is not None:
        if focal_px is None or distance_m is None:
            raise click.UsageError("--focal-px and --distance-m go together")
        calibration = {"intrinsics": {"focal_px": focal_px, "distance_m": distance_m}}
    if not calibration:
        raise click.UsageError("no calibration: give --marker-side-m (ArUco marker in the loop plane), "
                               "--focal-px with --distance-m, or a manifest with a calibration")
    result = identify(PhotoSet(photos=tuple(entries), calibration=calibration, loop_length_m=loop_len),
                      n_points=n_points, placement=placement, options=ExtractOptions(rope_polarity=rope_polarity),
                      workers=workers)
    path = write_identification(result, out_path, figures_dir=figures_dir)
    table = result.table
    for r in result.photos:
        ctx.note(f"{r.entry.path.name}: phi {r.entry.phi_deg:+g} deg, {r.entry.rope_speed_mps:g} m/s, "
                 f"loop {r.loop_length_m:.3f} m")
    ctx.result({"command": "identify", "table": str(path), "figures": None if figures_dir is None else str(figures_dir),
                "phi_deg": table.phi_deg.tolist(), "rope_speed_mps": table.rope_speed_mps.tolist(),
                "n_points": table.n_points, "placement": placement, "loop_length_m": round(table.loop_length_m, 4),
                "elapsed_s": round(result.elapsed_s, 3),
                "photos": [{"file": str(r.entry.path), "phi_deg": r.entry.phi_deg,
                            "rope_speed_mps": r.entry.rope_speed_mps, "loop_length_m": round(r.loop_length_m, 4)}
                           for r in result.photos]},
               f"wrote {path}: {table.rope_speed_mps.size} speed(s) x {table.phi_deg.size} phi x {table.n_points} "
               f"points, loop {table.loop_length_m:.3f} m, {len(result.photos)} photos in {result.elapsed_s:.1f} s")
