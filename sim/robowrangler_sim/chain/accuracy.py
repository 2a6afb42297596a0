"""Steady-state shape accuracy of the chain against the reference contour (the paper's Fig. 5a).

For each phi of the table: build the plant airborne in the target shape at that inclination, let it
settle for ``settle_s`` (the servos are first-order with tau = kd/kp = 0.5 s, the free lower branch
settles under gravity and the closure spring), then measure the distance from every chain point
(the N + 1 joint points, exit to last link end) to the reference contour polyline (the table's
contour at phi, scaled to the plant's loop length). Reported per phi: max and mean distance (m),
and their ratio to the loop length (the paper: max 4 cm on a 2 m loop, 2 %).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
from robowrangler_sim.shape_table import ShapeTable


def point_to_polyline_m(points_m: np.ndarray, polyline_m: np.ndarray) -> np.ndarray:
    """Distance of each point to a polyline. points_m: (K, 2); polyline_m: (M, 2). Returns (K,)."""
    a = polyline_m[:-1][None, :, :]
    b = polyline_m[1:][None, :, :]
    p = points_m[:, None, :]
    ab = b - a
    t = np.clip(np.sum((p - a) * ab, axis=2) / np.maximum(np.sum(ab * ab, axis=2), 1e-18), 0.0, 1.0)
    closest = a + t[..., None] * ab
    return np.min(np.linalg.norm(p - closest, axis=2), axis=1)


@dataclass(frozen=True)
class AccuracyReport:
    """Per-phi accuracy. Arrays have shape (P,) over ``phi_deg``.

    Attributes:
        phi_deg, max_m, mean_m: inclination, max and mean chain-to-contour distance.
        loop_length_m: loop length of the runs.
        chain_points_m: shape (P, N + 1, 2), settled chain in the table frame.
        reference_m: shape (P, M, 2), the reference contours (scaled to the loop length).
        closure_gap_m: shape (P,), closure gap at the end of each run.
    """

    phi_deg: np.ndarray
    max_m: np.ndarray
    mean_m: np.ndarray
    loop_length_m: float
    chain_points_m: np.ndarray
    reference_m: np.ndarray
    closure_gap_m: np.ndarray

    @property
    def worst_max_m(self) -> float:
        return float(np.max(self.max_m))

    def rows(self) -> list[dict]:
        return [dict(phi_deg=float(p), max_m=float(a), mean_m=float(b), max_pct=float(100 * a / self.loop_length_m))
                for p, a, b in zip(self.phi_deg, self.max_m, self.mean_m)]


def steady_state_accuracy(table: ShapeTable, *, params: ChainParams | None = None, settle_s: float = 4.0,
                          rope_speed_mps: float | None = None, phi_deg: np.ndarray | None = None) -> AccuracyReport:
    """Run the plant at every phi and measure the settled shape error (see module doc).

    Args:
        table: the reference shape table.
        params: chain parameters (default ChainParams()).
        settle_s: simulated settling time per phi, s.
        rope_speed_mps: rope speed (default: the table's highest speed).
        phi_deg: inclinations to test (default: the table's).
    """
    params = params if params is not None else ChainParams()
    speed = float(table.rope_speed_mps[-1]) if rope_speed_mps is None else float(rope_speed_mps)
    phis = table.phi_deg if phi_deg is None else np.asarray(phi_deg, dtype=float)
    maxs, means, chains, refs, gaps = [], [], [], [], []
    loop_len = params.home_loop_length_m
    for phi in phis:
        inputs = PlantInputs(rope_speed_mps=speed, guide_position_mm=0.0, base_pos_m=(0.0, 0.0, 2.0),
                             base_quat_wxyz=pitch_quat_wxyz(math.radians(float(phi))))
        plant = ChainPlant(table=table, params=params, initial=inputs, airborne=True)
        plant.advance(inputs, duration_s=settle_s)
        pts = plant.chain_points_loop_plane_m()
        ref = table.contour(float(phi), rope_speed_mps=speed)
        arc = float(np.sum(np.linalg.norm(np.diff(ref, axis=0), axis=1)))
        ref = ref * (loop_len / arc)
        dist = point_to_polyline_m(pts, ref)
        maxs.append(float(dist.max()))
        means.append(float(dist.mean()))
        chains.append(pts)
        refs.append(ref)
        gaps.append(plant.closure_gap_m())
    return AccuracyReport(phi_deg=np.asarray(phis, dtype=float), max_m=np.array(maxs), mean_m=np.array(means),
                          loop_length_m=loop_len, chain_points_m=np.array(chains), reference_m=np.array(refs),
                          closure_gap_m=np.array(gaps))


def plot_accuracy(report: AccuracyReport, path) -> None:
    """Two panels: chain vs reference contours; max/mean error over phi (cm). Writes a PNG at path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.8))
    cmap = plt.get_cmap("viridis")
    for k, phi in enumerate(report.phi_deg):
        c = cmap(k / max(len(report.phi_deg) - 1, 1))
        ax0.plot(report.reference_m[k, :, 0], report.reference_m[k, :, 1], "-", color=c, lw=1)
        ax0.plot(report.chain_points_m[k, :, 0], report.chain_points_m[k, :, 1], "o", color=c, ms=2.5)
    ax0.set_aspect("equal")
    ax0.set_xlabel("x (m)")
    ax0.set_ylabel("z (m)")
    ax0.set_title("reference contour (line) and settled chain (dots) per phi")
    ax1.plot(report.phi_deg, 100 * report.max_m, "o-", label="max")
    ax1.plot(report.phi_deg, 100 * report.mean_m, "s-", label="mean")
    ax1.axhline(4.0 * report.loop_length_m / 2.0, color="gray", ls="--", label="paper max (2 % of loop)")
    ax1.set_xlabel("phi (deg)")
    ax1.set_ylabel("distance to contour (cm)")
    ax1.set_title(f"steady-state accuracy, loop {report.loop_length_m:.2f} m")
    ax1.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Print the per-phi accuracy of the default (or synthetic, or --table) table and write the plot."""
    import argparse

    from robowrangler_sim.chain.default_table import default_or_synthetic_table

    ap = argparse.ArgumentParser(description="steady-state chain accuracy per phi (paper Fig. 5a)")
    ap.add_argument("--n-links", type=int, default=20)
    ap.add_argument("--settle-s", type=float, default=4.0)
    ap.add_argument("--out", default="chain_accuracy.png")
    ap.add_argument("--table", default=None, metavar="FILE",
                    help="a shape table (e.g. from `wrangler identify`) instead of the shipped default")
    args = ap.parse_args(argv)
    table = default_or_synthetic_table() if args.table is None else ShapeTable.load(args.table)
    report = steady_state_accuracy(table, params=ChainParams(n_links=args.n_links), settle_s=args.settle_s)
    print("phi_deg  max_cm  mean_cm  max_%")
    for row in report.rows():
        print(f"{row['phi_deg']:7.1f} {100 * row['max_m']:7.2f} {100 * row['mean_m']:8.2f} {row['max_pct']:6.2f}")
    plot_accuracy(report, args.out)
    print(f"worst max {100 * report.worst_max_m:.2f} cm on a {report.loop_length_m:.2f} m loop; plot {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
