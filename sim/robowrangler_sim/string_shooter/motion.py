"""Inputs of the string shooter over time: wheel surface speed and the module's pose (base translation,
inclination phi, heading yaw, guide travel), and where they put the eyelet's exit and return points.

Each input is a constant or a function of time that accepts a numpy array of times in seconds and
returns an array of the same length (shape (K,), or (K, 3) for the base position).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Union

import numpy as np

from .params import ModuleGeometry, StringShooterParamError

Signal = Union[float, Callable[[np.ndarray], np.ndarray]]


def _eval(name: str, sig, t_s: np.ndarray, width: int | None = None) -> np.ndarray:
    if callable(sig):
        out = np.asarray(sig(t_s), dtype=float)
    else:
        out = np.asarray(sig, dtype=float)
        out = np.broadcast_to(out, (t_s.size,) + out.shape).copy()
    expected = (t_s.size,) if width is None else (t_s.size, width)
    if out.shape != expected:
        try:
            out = np.broadcast_to(out, expected).copy()
        except ValueError:
            raise StringShooterParamError(f"{name}: expected shape {expected} for {t_s.size} times, got {out.shape}")
    if not np.all(np.isfinite(out)):
        raise StringShooterParamError(f"{name}: expected finite values, got NaN or infinity")
    return out


@dataclass(frozen=True)
class ModuleMotion:
    """Time-varying inputs.

    Attributes:
        wheel_speed_mps: wheel surface speed (what the nip tries to impose on the rope), m/s.
        phi_rad: inclination of the launch axis above the horizontal, rad.
        yaw_rad: heading of the launch axis about the vertical, rad.
        base_position_m: module origin in the world, shape (3,) or a function returning (K, 3).
        guide_travel_m: spindle-set guide travel from its base position, m (extending it shortens the loop
            by 2 m per metre).
    """

    wheel_speed_mps: Signal = 5.0
    phi_rad: Signal = 0.0
    yaw_rad: Signal = 0.0
    base_position_m: Signal = (0.0, 0.0, 0.0)
    guide_travel_m: Signal = 0.0

    def sample(self, t_s: np.ndarray, geometry: ModuleGeometry) -> dict[str, np.ndarray]:
        """Evaluate at times t_s (K,): returns wheel (K,), phi (K,), e1 (K,3), e3 (K,3), exit_m (K,3),
        return_m (K,3), return_dir (K,3) (direction of the rope on into the module at the return point),
        guide_m (K,3), travel_m (K,)."""
        t = np.asarray(t_s, dtype=float).reshape(-1)
        wheel = _eval("wheel_speed_mps", self.wheel_speed_mps, t)
        phi = _eval("phi_rad", self.phi_rad, t)
        yaw = _eval("yaw_rad", self.yaw_rad, t)
        base = _eval("base_position_m", self.base_position_m, t, 3)
        travel = _eval("guide_travel_m", self.guide_travel_m, t)
        if np.any(travel < -1e-9) or np.any(travel > geometry.guide_stroke_m + 1e-9):
            raise StringShooterParamError(
                f"guide_travel_m: expected values in [0, {geometry.guide_stroke_m}], "
                f"got [{travel.min():.4f}, {travel.max():.4f}]"
            )
        e1 = np.column_stack([np.cos(phi) * np.cos(yaw), np.cos(phi) * np.sin(yaw), np.sin(phi)])
        e2 = np.column_stack([-np.sin(yaw), np.cos(yaw), np.zeros_like(yaw)])
        e3 = np.cross(e1, e2)
        guide = base + (geometry.guide_base_m + travel)[:, None] * e1
        exit_m = guide + geometry.exit_offset_m * e3
        return_m = guide - geometry.return_offset_m * e3
        return_dir = -e1
        if geometry.span_m > 0:
            return_m = exit_m + geometry.span_m * e1
            return_dir = e1.copy()
        return {"return_dir": return_dir, "wheel": wheel, "phi": phi, "e1": e1, "e3": e3, "exit_m": exit_m, "return_m": return_m,
                "guide_m": guide, "travel_m": travel}
