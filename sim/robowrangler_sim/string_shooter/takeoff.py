"""Takeoff: the rope speed at which the loop leaves its hanging shape.

Physics: on the part of the loop that runs downward, tension grows by the axial drag f_t and falls by
the weight lambda g per metre; only when f_t(v) > lambda g can the effective tension T - lambda v^2
climb back through zero and turn the loop round in the air. Hence v* = sqrt(2 lambda g /
(rho C_f pi d)), the same for every loop length and launch angle (params.takeoff_speed_estimate_mps).

Measurement (what an observer with a ruler would do): the steady depth of the loop below the exit
point, as a fraction of half its length, compared with the same loop at the bracket's low speed, where
it hangs (checked against theory: below v* it hangs, and with the air switched off it hangs at every
speed); the loop has taken off when it has risen by more than ``threshold`` of half its length. The takeoff speed is found by bisection on the rope speed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .model import StringShooter
from .motion import ModuleMotion
from .params import AirParams, ShooterParams, StringShooterParamError


def loop_depth_m(points_xz_m: np.ndarray) -> float:
    """Depth of the lowest point below the exit, metres, for a contour (M, 2) in the loop frame."""
    return float(-np.min(points_xz_m[:, 1]))


def steady_depth_fraction(params: ShooterParams, *, rope_speed_mps: float, loop_length_m: float,
                          phi_rad: float, settle_s: float = 5.0, average_s: float = 0.5) -> float:
    """Mean depth / (loop length / 2) over the last ``average_s`` of a ``settle_s`` run from hanging."""
    motion = ModuleMotion(wheel_speed_mps=rope_speed_mps, phi_rad=phi_rad)
    sim = StringShooter(params, loop_length_m=loop_length_m, motion=motion, initial_shape="hanging")
    sim.step_for(max(settle_s - average_s, 0.0))
    depths = []
    for _ in range(5):
        sim.step_for(average_s / 5)
        depths.append(loop_depth_m(sim.frame().loop_plane_xz_m()))
    return float(np.mean(depths)) / (0.5 * loop_length_m)


@dataclass(frozen=True)
class TakeoffResult:
    """Measured takeoff speed with the sweep behind it.

    Attributes:
        speed_mps: rope speed at which the loop's depth leaves the hanging branch by ``threshold``.
        speeds_mps: shape (S,), the speeds swept.
        depth_fraction: shape (S,), steady depth / (loop length / 2) at each speed.
        baseline: (intercept, slope) of the hanging branch (depth fraction versus speed).
    """

    speed_mps: float
    speeds_mps: np.ndarray
    depth_fraction: np.ndarray
    baseline: tuple


def find_takeoff_speed(params: ShooterParams | None = None, *, loop_length_m: float = 2.0, phi_rad: float = 0.0,
                       speeds_mps=None, threshold: float = 0.03, baseline_below_mps: float = 2.1,
                       settle_s: float = 5.0) -> TakeoffResult:
    """Sweep the rope speed and find where the loop leaves the hanging branch.

    The hanging branch is the straight line fitted to the depth fractions at speeds up to
    ``baseline_below_mps`` (there f_t < 0.65 lambda g, deep in the hanging regime; the line slopes a
    little because the rope leaves the eyelet with momentum flux lambda v^2 and bends out before it
    hangs, which matters for short loops). The takeoff speed is where the depth first falls more than
    ``threshold`` below that line, interpolated linearly between sweep points.

    Args:
        speeds_mps: ascending speeds, shape (S,), default 1.5 .. 3.6 step 0.1 m/s.
    Raises StringShooterParamError if the loop never leaves the hanging branch in the sweep.
    """
    params = params or ShooterParams()
    speeds = np.arange(1.5, 3.61, 0.1) if speeds_mps is None else np.asarray(speeds_mps, dtype=float)
    if speeds.ndim != 1 or np.any(np.diff(speeds) <= 0):
        raise StringShooterParamError(f"speeds_mps: expected ascending speeds, got {speeds.tolist()}")
    baseline_points = int(np.sum(speeds <= baseline_below_mps + 1e-9))
    if baseline_points < 3 or baseline_points > speeds.size - 2:
        raise StringShooterParamError(
            f"speeds_mps: expected at least 3 speeds <= baseline_below_mps = {baseline_below_mps} and 2 above, "
            f"got {speeds.tolist()}"
        )
    depth = np.array([steady_depth_fraction(params, rope_speed_mps=float(v), loop_length_m=loop_length_m,
                                            phi_rad=phi_rad, settle_s=settle_s) for v in speeds])
    slope, intercept = np.polyfit(speeds[:baseline_points], depth[:baseline_points], 1)
    drop = intercept + slope * speeds - depth
    above = np.nonzero(drop[baseline_points:] > threshold)[0]
    if above.size == 0:
        raise StringShooterParamError(
            f"speeds_mps: the loop never took off up to {speeds[-1]:.2f} m/s (depth fractions {np.round(depth, 3).tolist()})"
        )
    k = baseline_points + int(above[0])
    v0, v1, d0, d1 = speeds[k - 1], speeds[k], drop[k - 1], drop[k]
    v_star = float(v0 + (threshold - d0) * (v1 - v0) / (d1 - d0)) if d1 != d0 else float(v1)
    return TakeoffResult(speed_mps=v_star, speeds_mps=speeds, depth_fraction=depth,
                         baseline=(float(intercept), float(slope)))


def no_air(params: ShooterParams) -> ShooterParams:
    """The same shooter in vacuum (air density zero)."""
    return replace(params, air=AirParams(density_kg_per_m3=0.0, wind_mps=params.air.wind_mps))
