"""Loop shape table: the steady airborne contour of the rope loop per inclination phi (and rope speed).

The table is what the chain model (the paper's empirical model) replays: for each manipulator
inclination phi the loop's contour, as N points equally spaced along the rope, interpolated over phi
with cubic splines. It is produced by shape identification from photos, or by the first-principles
string-shooter simulator when no photos exist.

File format (JSON, schema ``robowrangler.shape_table/1``)::

    {
      "schema": "robowrangler.shape_table/1",
      "source": "free text: where the contours come from",
      "loop_length_m": 2.0,             # rope length outside the guide when the contours were taken
      "rope_speed_mps": [5.0],          # ascending, one entry per speed
      "phi_deg": [-30, -25, ..., 40],   # ascending manipulator inclinations
      "contours_m": [                   # [speed][phi][point][x, z]
        [[[x, z], ...], ...]
      ]
    }

Frame and ordering: points lie in the loop plane, in metres, origin at the guide exit, x horizontal and
pointing away from the robot (the launch direction projected on the horizontal), z up (gravity is -z).
phi is the inclination of the module's launch axis above the horizontal. Each contour starts at the
exit point, runs out along the upper branch, round the tip and back along the lower branch, and ends at
the return point (first and last point included). Tables from the simulator space the points equally in
arc length; `wrangler identify` (robowrangler_sim.identify) by default places them densest round the tip,
with the tip itself a point at the same index at every phi. Consumers resample by arc length (the chain:
chain/targets.py) and so read either.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

SCHEMA = "robowrangler.shape_table/1"


class ShapeTableError(ValueError):
    """A shape table file or array is malformed; the message names the field, expected and actual."""


@dataclass(frozen=True)
class ShapeTable:
    """Contours of the airborne loop per (rope speed, phi).

    Attributes:
        phi_deg: shape (P,), ascending inclinations in degrees.
        rope_speed_mps: shape (S,), ascending rope speeds in m/s.
        contours_m: shape (S, P, N, 2), points (x, z) in metres, frame and order as in the module doc.
        loop_length_m: rope length outside the guide for these contours, metres.
        source: where the contours come from.
    """

    phi_deg: np.ndarray
    rope_speed_mps: np.ndarray
    contours_m: np.ndarray
    loop_length_m: float
    source: str

    def __post_init__(self) -> None:
        phi = np.asarray(self.phi_deg, dtype=float)
        speed = np.asarray(self.rope_speed_mps, dtype=float)
        contours = np.asarray(self.contours_m, dtype=float)
        if phi.ndim != 1 or phi.size < 2:
            raise ShapeTableError(f"phi_deg: expected at least 2 angles in a 1-D list, got shape {phi.shape}")
        if np.any(np.diff(phi) <= 0):
            raise ShapeTableError(f"phi_deg: expected strictly ascending angles, got {phi.tolist()}")
        if speed.ndim != 1 or speed.size < 1 or np.any(np.diff(speed) <= 0) or np.any(speed <= 0):
            raise ShapeTableError(
                f"rope_speed_mps: expected ascending positive speeds, got {speed.tolist()}"
            )
        expected = (speed.size, phi.size)
        if contours.ndim != 4 or contours.shape[:2] != expected or contours.shape[3] != 2:
            raise ShapeTableError(
                f"contours_m: expected shape ({expected[0]}, {expected[1]}, N, 2), got {contours.shape}"
            )
        if contours.shape[2] < 4:
            raise ShapeTableError(f"contours_m: expected at least 4 points per contour, got {contours.shape[2]}")
        if not np.all(np.isfinite(contours)):
            raise ShapeTableError("contours_m: expected finite numbers, found NaN or infinity")
        if not (self.loop_length_m > 0 and np.isfinite(self.loop_length_m)):
            raise ShapeTableError(f"loop_length_m: expected a positive length, got {self.loop_length_m!r}")
        object.__setattr__(self, "phi_deg", phi)
        object.__setattr__(self, "rope_speed_mps", speed)
        object.__setattr__(self, "contours_m", contours)

    @property
    def n_points(self) -> int:
        return int(self.contours_m.shape[2])

    def contour(self, phi_deg: float, *, rope_speed_mps: float | None = None) -> np.ndarray:
        """Contour at an inclination, cubic spline over phi (clamped to the table's range).

        Speed: the nearest tabulated speed at or below ``rope_speed_mps`` (the highest when None).
        Returns shape (N, 2), metres.
        """
        if rope_speed_mps is None:
            s = self.rope_speed_mps.size - 1
        else:
            s = int(np.clip(np.searchsorted(self.rope_speed_mps, rope_speed_mps, side="right") - 1,
                            0, self.rope_speed_mps.size - 1))
        phi = float(np.clip(phi_deg, self.phi_deg[0], self.phi_deg[-1]))
        spline = self._spline(s)
        return spline(phi)

    def _spline(self, speed_index: int) -> CubicSpline:
        cache = self.__dict__.setdefault("_splines", {})
        if speed_index not in cache:
            cache[speed_index] = CubicSpline(self.phi_deg, self.contours_m[speed_index], axis=0)
        return cache[speed_index]

    # --- files -----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        return {
            "schema": SCHEMA,
            "source": self.source,
            "loop_length_m": float(self.loop_length_m),
            "rope_speed_mps": self.rope_speed_mps.tolist(),
            "phi_deg": self.phi_deg.tolist(),
            "contours_m": np.round(self.contours_m, 6).tolist(),
        }

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return path

    @classmethod
    def from_dict(cls, data: dict) -> "ShapeTable":
        if not isinstance(data, dict):
            raise ShapeTableError(f"shape table: expected a JSON object, got {type(data).__name__}")
        if data.get("schema") != SCHEMA:
            raise ShapeTableError(f"schema: expected {SCHEMA!r}, got {data.get('schema')!r}")
        missing = [k for k in ("phi_deg", "rope_speed_mps", "contours_m", "loop_length_m") if k not in data]
        if missing:
            raise ShapeTableError(f"shape table: missing field(s) {missing}")
        try:
            return cls(
                phi_deg=np.asarray(data["phi_deg"], dtype=float),
                rope_speed_mps=np.asarray(data["rope_speed_mps"], dtype=float),
                contours_m=np.asarray(data["contours_m"], dtype=float),
                loop_length_m=float(data["loop_length_m"]),
                source=str(data.get("source", "")),
            )
        except (TypeError, ValueError) as exc:
            if isinstance(exc, ShapeTableError):
                raise
            raise ShapeTableError(f"shape table: non-numeric or ragged data ({exc})") from exc

    @classmethod
    def load(cls, path: str | Path) -> "ShapeTable":
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise ShapeTableError(f"{path}: not valid JSON ({exc})") from exc
        return cls.from_dict(data)


def resample_by_arc_length(points_m: np.ndarray, n_points: int) -> np.ndarray:
    """Resample a polyline to ``n_points`` points equally spaced in arc length (ends kept).

    Args:
        points_m: shape (M, 2), M >= 2.
    Returns: shape (n_points, 2).
    """
    pts = np.asarray(points_m, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 2:
        raise ShapeTableError(f"points_m: expected shape (M>=2, 2), got {pts.shape}")
    if n_points < 2:
        raise ShapeTableError(f"n_points: expected >= 2, got {n_points}")
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        raise ShapeTableError("points_m: polyline has zero length")
    target = np.linspace(0.0, s[-1], n_points)
    return np.column_stack([np.interp(target, s, pts[:, 0]), np.interp(target, s, pts[:, 1])])
