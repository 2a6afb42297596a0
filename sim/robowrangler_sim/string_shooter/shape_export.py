"""The default shape table from first principles: steady loop contours per inclination phi and rope
speed, in the ShapeTable format the chain model reads (robowrangler_sim.shape_table).

Regenerate the committed default:

    uv run python -m robowrangler_sim.string_shooter.shape_export \
        --out sim/robowrangler_sim/data/shape_table_default.json
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from ..shape_table import ShapeTable, ShapeTableError, resample_by_arc_length
from .model import StringShooter
from .motion import ModuleMotion
from .params import ShooterParams, StringShooterParamError

DEFAULT_PHI_DEG = tuple(range(-30, 41, 5))
DEFAULT_SPEEDS_MPS = (4.0, 5.0, 8.0)
DEFAULT_TABLE_PATH = Path(__file__).resolve().parents[1] / "data" / "shape_table_default.json"


def steady_contour_xz_m(params: ShooterParams, *, phi_deg: float, rope_speed_mps: float, loop_length_m: float,
                        n_points: int, settle_s: float = 6.0, average_s: float = 1.0) -> np.ndarray:
    """Time-averaged steady contour, shape (n_points, 2), loop frame, equally spaced in arc length.

    Each sampled frame is resampled finely (10 x n_points) first, so the average is taken point by point
    at equal arc-length fractions; the mean is then resampled to n_points.
    """
    motion = ModuleMotion(wheel_speed_mps=rope_speed_mps, phi_rad=np.radians(phi_deg))
    sim = StringShooter(params, loop_length_m=loop_length_m, motion=motion, initial_shape="circle")
    sim.step_for(max(settle_s - average_s, 0.0))
    samples = []
    for _ in range(10):
        sim.step_for(average_s / 10)
        samples.append(resample_by_arc_length(sim.frame().loop_plane_xz_m(), 10 * n_points))
    return resample_by_arc_length(np.mean(samples, axis=0), n_points)


def make_shape_table(params: ShooterParams | None = None, *, phi_deg=DEFAULT_PHI_DEG,
                     rope_speeds_mps=DEFAULT_SPEEDS_MPS, loop_length_m: float = 2.0, n_points: int = 40,
                     settle_s: float = 6.0, progress: bool = False) -> ShapeTable:
    """Simulate every (speed, phi) to steady state and collect the contours into a ShapeTable.

    Args:
        phi_deg: ascending inclinations, degrees; rope_speeds_mps: ascending speeds above takeoff, m/s.
        n_points: contour points per shape.
    """
    params = params or ShooterParams()
    phis = [float(p) for p in phi_deg]
    speeds = [float(v) for v in rope_speeds_mps]
    if n_points < 4:
        raise StringShooterParamError(f"n_points: expected >= 4, got {n_points}")
    if len(speeds) < 1 or np.any(np.diff(speeds) <= 0) or min(speeds) <= 0:
        raise StringShooterParamError(f"rope_speed_mps: expected ascending distinct positive speeds, got {speeds}")
    if len(phis) < 2 or np.any(np.diff(phis) <= 0):
        raise StringShooterParamError(f"phi_deg: expected at least 2 ascending angles, got {phis}")
    contours = np.zeros((len(speeds), len(phis), n_points, 2))
    t0 = time.perf_counter()
    total = len(speeds) * len(phis)
    for si, v in enumerate(speeds):
        for pi, phi in enumerate(phis):
            contours[si, pi] = steady_contour_xz_m(params, phi_deg=phi, rope_speed_mps=v,
                                                   loop_length_m=loop_length_m, n_points=n_points,
                                                   settle_s=settle_s)
            if progress:
                done = si * len(phis) + pi + 1
                print(f"\r  shape table: {done}/{total} (v = {v} m/s, phi = {phi:+.0f} deg), "
                      f"{time.perf_counter() - t0:.0f} s", end="", file=sys.stderr, flush=True)
    if progress:
        print("", file=sys.stderr)
    rope = params.rope
    source = (f"robowrangler_sim.string_shooter first-principles simulator: lambda = "
              f"{rope.linear_density_kg_per_m * 1e3:.3f} g/m, d = {rope.diameter_m * 1e3:.1f} mm, C_f = "
              f"{rope.skin_friction_coeff}, C_n = {rope.normal_drag_coeff}, B = {rope.bending_stiffness_n_m2} N m2, "
              f"rho = {params.air.density_kg_per_m3} kg/m3, segment {params.numerics.segment_length_m} m, "
              f"settle {settle_s} s, mean of the last 1 s")
    return ShapeTable(phi_deg=np.array(phis), rope_speed_mps=np.array(speeds), contours_m=contours,
                      loop_length_m=loop_length_m, source=source)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_TABLE_PATH, help="output JSON path")
    ap.add_argument("--speeds", type=float, nargs="+", default=list(DEFAULT_SPEEDS_MPS), help="rope speeds, m/s")
    ap.add_argument("--loop-length", type=float, default=2.0, help="loop length outside the guide, m")
    ap.add_argument("--points", type=int, default=40, help="contour points per shape")
    ap.add_argument("--settle", type=float, default=6.0, help="simulated settling time per shape, s")
    args = ap.parse_args(argv)
    try:
        table = make_shape_table(rope_speeds_mps=sorted(args.speeds), loop_length_m=args.loop_length,
                                 n_points=args.points, settle_s=args.settle, progress=True)
        table.save(args.out)
    except (StringShooterParamError, ShapeTableError, OSError) as exc:
        print(f"shape_export: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}: {len(table.rope_speed_mps)} speeds x {len(table.phi_deg)} phi x {table.n_points} points",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
