"""The chain model's wrangling objects as static string-shooter obstacles (same shapes, same pose).

``obstacles_for_placement`` reads an ``ObjectPlacement`` of robowrangler_sim.chain.objects (duck-typed:
``placement.spec.geoms`` with ``type``, ``size_m``, ``pos_m``, ``euler_rad`` in MuJoCo conventions, and
``placement.pos_m``, ``placement.yaw_rad``) and returns Sphere / Cylinder / Capsule / Box obstacles
in the world frame with the object's friction. Objects are static here: the string shooter is the
reference for the rope, not for the object's motion.
"""

from __future__ import annotations

import numpy as np

from .contact import Box, Capsule, Cylinder, Sphere
from .params import StringShooterParamError


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def euler_xyz_intrinsic(euler_rad) -> np.ndarray:
    """MuJoCo's default euler sequence ("xyz", rotating axes): R = Rx(a) Ry(b) Rz(c). Shape (3, 3)."""
    a, b, c = (float(x) for x in euler_rad)
    return _rot_x(a) @ _rot_y(b) @ _rot_z(c)


def obstacles_for_placement(placement) -> list:
    """Static obstacles for one placed chain-model object. Returns a list of obstacle objects."""
    spec = placement.spec
    body_rot = _rot_z(float(placement.yaw_rad))
    origin = np.asarray(placement.pos_m, dtype=float)
    mu = float(spec.friction)
    out = []
    for k, g in enumerate(spec.geoms):
        rot = body_rot @ euler_xyz_intrinsic(g.euler_rad)
        center = origin + body_rot @ np.asarray(g.pos_m, dtype=float)
        size = tuple(float(s) for s in g.size_m)
        if g.type == "sphere":
            out.append(Sphere(center_m=tuple(center), radius_m=size[0], friction_coeff=mu))
        elif g.type == "box":
            out.append(Box(center_m=tuple(center), half_extents_m=size, rotation=tuple(map(tuple, rot)),
                           friction_coeff=mu))
        elif g.type in ("cylinder", "capsule"):
            axis = rot[:, 2] * size[1]
            cls = Cylinder if g.type == "cylinder" else Capsule
            out.append(cls(end_a_m=tuple(center - axis), end_b_m=tuple(center + axis), radius_m=size[0],
                           friction_coeff=mu))
        else:
            raise StringShooterParamError(
                f"placement.spec.geoms[{k}].type: expected sphere, box, cylinder or capsule, got {g.type!r}"
            )
    return out
