"""Obstacles the rope can touch: sphere, cylinder (flat ends, e.g. a door handle bar), capsule, box
(also a flat plate), half-space (ground). Obstacles are static. Penalty contact with regularised Coulomb friction.

Each obstacle packs into one row of ``OBSTACLE_ROW`` floats for the compiled kernel:
``[kind, mu, p0..p12]``; the signed-distance function itself is compiled in kernel.py (one file, so
that numba's on-disk cache is invalidated whenever it changes); ``signed_distance_m`` evaluates it
for tests and plots. Contact acts on rope nodes: normal force k (r_rope - sdf) - c v_n while sdf < r_rope, friction
-mu F_n v_t / max(|v_t|, v_reg).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kernel import KIND_BOX, KIND_CAPSULE, KIND_CYLINDER, KIND_HALFSPACE, KIND_SPHERE, OBSTACLE_ROW, sdf_one
from .params import StringShooterParamError



def _vec3(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise StringShooterParamError(f"{name}: expected 3 finite numbers, got {value!r}")
    return arr


def _positive(name: str, value: float) -> float:
    if not (np.isfinite(value) and value > 0):
        raise StringShooterParamError(f"{name}: expected a positive number, got {value!r}")
    return float(value)


def _friction(mu: float) -> float:
    if not (np.isfinite(mu) and mu >= 0):
        raise StringShooterParamError(f"friction_coeff: expected >= 0, got {mu!r}")
    return float(mu)


@dataclass(frozen=True)
class Sphere:
    """Sphere; center_m shape (3,), world frame."""

    center_m: tuple
    radius_m: float
    friction_coeff: float = 0.5

    def row(self) -> np.ndarray:
        r = np.zeros(OBSTACLE_ROW)
        r[0], r[1] = KIND_SPHERE, _friction(self.friction_coeff)
        r[2:5] = _vec3("center_m", self.center_m)
        r[5] = _positive("radius_m", self.radius_m)
        return r


def _segment_row(kind, name_a, a, name_b, b, radius_m, mu):
    r = np.zeros(OBSTACLE_ROW)
    r[0], r[1] = kind, _friction(mu)
    a, b = _vec3(name_a, a), _vec3(name_b, b)
    if np.linalg.norm(b - a) <= 0:
        raise StringShooterParamError(f"{name_b}: expected a point distinct from {name_a}, got the same point")
    r[2:5], r[5:8] = a, b
    r[8] = _positive("radius_m", radius_m)
    return r


@dataclass(frozen=True)
class Capsule:
    """Cylinder with hemispherical ends from end_a_m to end_b_m (each shape (3,))."""

    end_a_m: tuple
    end_b_m: tuple
    radius_m: float
    friction_coeff: float = 0.5

    def row(self) -> np.ndarray:
        return _segment_row(KIND_CAPSULE, "end_a_m", self.end_a_m, "end_b_m", self.end_b_m, self.radius_m,
                            self.friction_coeff)


@dataclass(frozen=True)
class Cylinder:
    """Solid cylinder with flat ends, axis from end_a_m to end_b_m (each shape (3,)); a door handle bar."""

    end_a_m: tuple
    end_b_m: tuple
    radius_m: float
    friction_coeff: float = 0.5

    def row(self) -> np.ndarray:
        return _segment_row(KIND_CYLINDER, "end_a_m", self.end_a_m, "end_b_m", self.end_b_m, self.radius_m,
                            self.friction_coeff)


@dataclass(frozen=True)
class Box:
    """Box: center_m (3,), half_extents_m (3,), rotation (3, 3) body-to-world. A thin box is a flat plate."""

    center_m: tuple
    half_extents_m: tuple
    rotation: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    friction_coeff: float = 0.5

    def row(self) -> np.ndarray:
        r = np.zeros(OBSTACLE_ROW)
        r[0], r[1] = KIND_BOX, _friction(self.friction_coeff)
        r[2:5] = _vec3("center_m", self.center_m)
        h = _vec3("half_extents_m", self.half_extents_m)
        if np.any(h <= 0):
            raise StringShooterParamError(f"half_extents_m: expected positive values, got {h.tolist()}")
        rot = np.asarray(self.rotation, dtype=float)
        if rot.shape != (3, 3) or not np.allclose(rot @ rot.T, np.eye(3), atol=1e-6):
            raise StringShooterParamError(f"rotation: expected a 3x3 rotation matrix, got {rot.tolist()}")
        r[5:8] = h
        # only the 3 columns (body axes in world) are needed: 9 numbers do not fit; keep x and z axes
        r[8:11], r[11:14] = rot[:, 0], rot[:, 2]
        return r


@dataclass(frozen=True)
class HalfSpace:
    """Everything below the plane through point_m with outward normal normal_m (e.g. the ground)."""

    point_m: tuple = (0.0, 0.0, 0.0)
    normal_m: tuple = (0.0, 0.0, 1.0)
    friction_coeff: float = 0.5

    def row(self) -> np.ndarray:
        r = np.zeros(OBSTACLE_ROW)
        r[0], r[1] = KIND_HALFSPACE, _friction(self.friction_coeff)
        r[2:5] = _vec3("point_m", self.point_m)
        n = _vec3("normal_m", self.normal_m)
        if np.linalg.norm(n) <= 0:
            raise StringShooterParamError("normal_m: expected a non-zero vector, got zeros")
        r[5:8] = n / np.linalg.norm(n)
        return r


def pack_obstacles(obstacles) -> np.ndarray:
    """Pack obstacle objects into an array of shape (K, OBSTACLE_ROW) for the kernel."""
    rows = []
    for i, ob in enumerate(obstacles or ()):
        if not hasattr(ob, "row"):
            raise StringShooterParamError(
                f"obstacles[{i}]: expected Sphere, Cylinder, Capsule, Box or HalfSpace, got {type(ob).__name__}"
            )
        rows.append(ob.row())
    return np.array(rows, dtype=float).reshape(len(rows), OBSTACLE_ROW)


def signed_distance_m(obstacle, points_m: np.ndarray) -> np.ndarray:
    """Signed distance of points (M, 3) to one obstacle, metres (negative inside). Returns (M,)."""
    row = obstacle.row()
    pts = np.asarray(points_m, dtype=float).reshape(-1, 3)
    normal = np.zeros(3)
    return np.array([sdf_one(row, p, normal) for p in pts])
