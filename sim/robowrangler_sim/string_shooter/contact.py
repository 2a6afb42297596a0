"""Obstacles the rope can touch: sphere, cylinder (capped, e.g. a door handle), box (also a flat
plate), half-space (ground). Penalty contact with regularised Coulomb friction.

Each obstacle packs into one row of ``OBSTACLE_ROW`` floats for the compiled kernel:
``[kind, mu, p0..p12]``; ``signed_distance_m`` evaluates the same geometry in numpy for tests and
plots. Contact acts on rope nodes: normal force k (r_rope - sdf) - c v_n while sdf < r_rope, friction
-mu F_n v_t / max(|v_t|, v_reg).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .params import StringShooterParamError

OBSTACLE_ROW = 16
KIND_SPHERE, KIND_CYLINDER, KIND_BOX, KIND_HALFSPACE = 0, 1, 2, 3


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


@dataclass(frozen=True)
class Cylinder:
    """Cylinder with rounded ends (capsule) from end_a_m to end_b_m (each shape (3,)); a door handle too."""

    end_a_m: tuple
    end_b_m: tuple
    radius_m: float
    friction_coeff: float = 0.5

    def row(self) -> np.ndarray:
        r = np.zeros(OBSTACLE_ROW)
        r[0], r[1] = KIND_CYLINDER, _friction(self.friction_coeff)
        a, b = _vec3("end_a_m", self.end_a_m), _vec3("end_b_m", self.end_b_m)
        if np.linalg.norm(b - a) <= 0:
            raise StringShooterParamError("end_b_m: expected a point distinct from end_a_m, got the same point")
        r[2:5], r[5:8] = a, b
        r[8] = _positive("radius_m", self.radius_m)
        return r


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
                f"obstacles[{i}]: expected Sphere, Cylinder, Box or HalfSpace, got {type(ob).__name__}"
            )
        rows.append(ob.row())
    return np.array(rows, dtype=float).reshape(len(rows), OBSTACLE_ROW)


@njit(cache=True)
def sdf_one(row, x, out_normal):
    """Signed distance (m) of point x (3,) to the obstacle row; writes the outward unit normal."""
    kind = int(row[0])
    if kind == KIND_SPHERE:
        dx, dy, dz = x[0] - row[2], x[1] - row[3], x[2] - row[4]
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)
        if dist < 1e-12:
            out_normal[0], out_normal[1], out_normal[2] = 0.0, 0.0, 1.0
        else:
            out_normal[0], out_normal[1], out_normal[2] = dx / dist, dy / dist, dz / dist
        return dist - row[5]
    if kind == KIND_CYLINDER:
        ax, ay, az = row[2], row[3], row[4]
        bx, by, bz = row[5] - ax, row[6] - ay, row[7] - az
        px, py, pz = x[0] - ax, x[1] - ay, x[2] - az
        t = (px * bx + py * by + pz * bz) / (bx * bx + by * by + bz * bz)
        t = min(max(t, 0.0), 1.0)
        dx, dy, dz = px - t * bx, py - t * by, pz - t * bz
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)
        if dist < 1e-12:
            out_normal[0], out_normal[1], out_normal[2] = 0.0, 0.0, 1.0
        else:
            out_normal[0], out_normal[1], out_normal[2] = dx / dist, dy / dist, dz / dist
        return dist - row[8]
    if kind == KIND_BOX:
        ex0, ex1, ex2 = row[8], row[9], row[10]
        ez0, ez1, ez2 = row[11], row[12], row[13]
        ey0, ey1, ey2 = ez1 * ex2 - ez2 * ex1, ez2 * ex0 - ez0 * ex2, ez0 * ex1 - ez1 * ex0
        px, py, pz = x[0] - row[2], x[1] - row[3], x[2] - row[4]
        lx = px * ex0 + py * ex1 + pz * ex2
        ly = px * ey0 + py * ey1 + pz * ey2
        lz = px * ez0 + py * ez1 + pz * ez2
        qx, qy, qz = abs(lx) - row[5], abs(ly) - row[6], abs(lz) - row[7]
        if qx > 0 or qy > 0 or qz > 0:
            ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
            dist = np.sqrt(ox * ox + oy * oy + oz * oz)
            nx, ny, nz = ox / dist * np.sign(lx), oy / dist * np.sign(ly), oz / dist * np.sign(lz)
        else:
            nx, ny, nz = 0.0, 0.0, 0.0
            if qx >= qy and qx >= qz:
                dist, nx = qx, np.sign(lx)
            elif qy >= qz:
                dist, ny = qy, np.sign(ly)
            else:
                dist, nz = qz, np.sign(lz)
        out_normal[0] = nx * ex0 + ny * ey0 + nz * ez0
        out_normal[1] = nx * ex1 + ny * ey1 + nz * ez1
        out_normal[2] = nx * ex2 + ny * ey2 + nz * ez2
        return dist
    # half-space
    out_normal[0], out_normal[1], out_normal[2] = row[5], row[6], row[7]
    return (x[0] - row[2]) * row[5] + (x[1] - row[3]) * row[6] + (x[2] - row[4]) * row[7]


def signed_distance_m(obstacle, points_m: np.ndarray) -> np.ndarray:
    """Signed distance of points (M, 3) to one obstacle, metres (negative inside). Returns (M,)."""
    row = obstacle.row()
    pts = np.asarray(points_m, dtype=float).reshape(-1, 3)
    normal = np.zeros(3)
    return np.array([sdf_one(row, p, normal) for p in pts])
