"""Objects for wrangling: real sizes, masses and frictions, built from MuJoCo primitives.

The household objects are those of the paper's Table I (YCB-like items); sizes and masses are the
published YCB object-set figures where one exists (rounded), otherwise typical retail items; the
sliding friction is an estimate of rope-on-surface friction per material (wool on cardboard, metal,
ceramic, felt, ...) and is the value MuJoCo uses for the pair (the rope's own friction is lower,
and MuJoCo takes the larger of the two). Every shape is a set of primitives in one body, positioned
so that the body's origin is at the object's lowest point, on the centre line, when it rests upright.

``shape_class`` groups objects as the paper's qualitative result does: "cylinder" and "box" objects
are expected to be secured by the loop, "sphere" objects to slip out; irregular shapes carry no
expectation (None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from robowrangler_sim.chain.errors import ChainModelError

GEOM_TYPES = ("box", "cylinder", "sphere", "capsule")
SHAPE_CLASSES = ("cylinder", "box", "sphere", "irregular", "fixture")


@dataclass(frozen=True, kw_only=True)
class GeomSpec:
    """One primitive of an object.

    Attributes:
        type: "box" | "cylinder" | "sphere" | "capsule".
        size_m: MuJoCo size: box half-extents (3), cylinder/capsule (radius, half-length),
            sphere (radius,).
        pos_m: shape (3,), centre in the body frame.
        euler_rad: shape (3,), xyz Euler rotation of the primitive (cylinders/capsules run along z).
        rgba: colour.
    """

    type: str
    size_m: tuple[float, ...]
    pos_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    euler_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rgba: tuple[float, float, float, float] = (0.6, 0.6, 0.6, 1.0)

    def __post_init__(self) -> None:
        if self.type not in GEOM_TYPES:
            raise ChainModelError(f"type: expected one of {GEOM_TYPES}, got {self.type!r}")
        n = {"box": 3, "cylinder": 2, "capsule": 2, "sphere": 1}[self.type]
        if len(self.size_m) != n or any(not (s > 0 and math.isfinite(s)) for s in self.size_m):
            raise ChainModelError(f"size_m: expected {n} positive sizes for a {self.type}, got {self.size_m}")

    def volume_m3(self) -> float:
        s = self.size_m
        if self.type == "box":
            return 8 * s[0] * s[1] * s[2]
        if self.type == "cylinder":
            return math.pi * s[0] ** 2 * 2 * s[1]
        if self.type == "capsule":
            return math.pi * s[0] ** 2 * 2 * s[1] + 4 / 3 * math.pi * s[0] ** 3
        return 4 / 3 * math.pi * s[0] ** 3


@dataclass(frozen=True, kw_only=True)
class ObjectSpec:
    """A wrangling object.

    Attributes:
        name: catalogue key (MJCF body name prefix).
        geoms: the primitives; total mass is distributed by volume.
        mass_kg: total mass (ignored for fixtures).
        friction: sliding friction coefficient of its surface against the rope and floor.
        shape_class: see module doc.
        free: True for a free-moving object, False for a fixture welded to the world.
        source: where the numbers come from.
    """

    name: str
    geoms: tuple[GeomSpec, ...]
    mass_kg: float
    friction: float
    shape_class: str
    free: bool = True
    source: str = ""
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ChainModelError(f"name: expected an identifier, got {self.name!r}")
        if not self.geoms:
            raise ChainModelError("geoms: expected at least one primitive, got none")
        if self.free and not (self.mass_kg > 0 and math.isfinite(self.mass_kg)):
            raise ChainModelError(f"mass_kg: expected > 0 for a free object, got {self.mass_kg}")
        if not 0.0 < self.friction <= 3.0:
            raise ChainModelError(f"friction: expected in (0, 3], got {self.friction}")
        if self.shape_class not in SHAPE_CLASSES:
            raise ChainModelError(f"shape_class: expected one of {SHAPE_CLASSES}, got {self.shape_class!r}")

    @property
    def expected_outcome(self) -> str | None:
        """The paper's qualitative expectation: "secured", "slips" or None."""
        return {"cylinder": "secured", "box": "secured", "sphere": "slips"}.get(self.shape_class)

    def geom_masses_kg(self) -> list[float]:
        vols = [g.volume_m3() for g in self.geoms]
        total = sum(vols)
        return [self.mass_kg * v / total for v in vols]

    @property
    def height_m(self) -> float:
        """Top of the highest primitive above the body origin (approximate for rotated ones)."""
        top = 0.0
        for g in self.geoms:
            upright = g.euler_rad == (0.0, 0.0, 0.0)
            if g.type == "box":
                extent = g.size_m[2] if upright else max(g.size_m)
            elif g.type == "sphere":
                extent = g.size_m[0]
            elif g.type == "cylinder":
                extent = g.size_m[1] if upright else g.size_m[0]
            else:
                extent = g.size_m[1] + g.size_m[0] if upright else g.size_m[0]
            top = max(top, g.pos_m[2] + extent)
        return top


def _upright_cylinder(radius_m, height_m, rgba):
    return GeomSpec(type="cylinder", size_m=(radius_m, height_m / 2), pos_m=(0, 0, height_m / 2), rgba=rgba)


def _lying(kind, radius_m, length_m, z_m, rgba, *, x_m=0.0, y_m=0.0, yaw_rad=0.0):
    # primitive along z rotated to lie along x (then yawed)
    return GeomSpec(type=kind, size_m=(radius_m, length_m / 2), pos_m=(x_m, y_m, z_m),
                    euler_rad=(0.0, math.pi / 2, yaw_rad), rgba=rgba)


def _sphere(radius_m, rgba):
    return GeomSpec(type="sphere", size_m=(radius_m,), pos_m=(0, 0, radius_m), rgba=rgba)


def _box(lx, ly, lz, rgba):
    return GeomSpec(type="box", size_m=(lx / 2, ly / 2, lz / 2), pos_m=(0, 0, lz / 2), rgba=rgba)


YCB = "YCB object set (Calli et al. 2015) published size/mass, rounded"


def _catalogue() -> dict[str, ObjectSpec]:
    red, yellow, white = (0.8, 0.15, 0.1, 1), (0.95, 0.85, 0.2, 1), (0.92, 0.92, 0.9, 1)
    objs = [
        ObjectSpec(name="chips_can", geoms=(_upright_cylinder(0.0375, 0.250, red),), mass_kg=0.205,
                   friction=0.5, shape_class="cylinder", source=YCB + "; cardboard"),
        ObjectSpec(name="tuna_can", geoms=(_upright_cylinder(0.0425, 0.033, (0.7, 0.7, 0.75, 1)),),
                   mass_kg=0.171, friction=0.3, shape_class="cylinder", source=YCB + "; tinplate"),
        ObjectSpec(name="banana", geoms=(
            _lying("capsule", 0.018, 0.070, 0.018, yellow, x_m=-0.060, y_m=0.015, yaw_rad=0.35),
            _lying("capsule", 0.018, 0.070, 0.018, yellow),
            _lying("capsule", 0.018, 0.070, 0.018, yellow, x_m=0.060, y_m=0.015, yaw_rad=-0.35)),
            mass_kg=0.066, friction=0.4, shape_class="irregular", source=YCB + "; three capsules"),
        ObjectSpec(name="sponge", geoms=(_box(0.114, 0.072, 0.014, (0.3, 0.7, 0.3, 1)),), mass_kg=0.0062,
                   friction=0.9, shape_class="box", source=YCB),
        ObjectSpec(name="mug", geoms=(
            _upright_cylinder(0.040, 0.082, (0.9, 0.3, 0.2, 1)),
            GeomSpec(type="capsule", size_m=(0.006, 0.022), pos_m=(0.055, 0, 0.041), rgba=(0.9, 0.3, 0.2, 1))),
            mass_kg=0.118, friction=0.4, shape_class="cylinder", source=YCB + "; glazed ceramic, handle"),
        ObjectSpec(name="marker", geoms=(_lying("cylinder", 0.009, 0.121, 0.009, (0.1, 0.1, 0.1, 1)),),
                   mass_kg=0.0158, friction=0.35, shape_class="irregular", source=YCB + " (large marker)"),
        ObjectSpec(name="screwdriver", geoms=(
            _lying("cylinder", 0.0155, 0.090, 0.0155, (0.9, 0.7, 0.1, 1), x_m=-0.0625),
            _lying("cylinder", 0.003, 0.125, 0.0155, (0.7, 0.7, 0.7, 1), x_m=0.045)),
            mass_kg=0.0975, friction=0.4, shape_class="irregular", source=YCB + " (phillips)"),
        ObjectSpec(name="credit_card", geoms=(_box(0.0856, 0.05398, 0.00076, (0.2, 0.3, 0.8, 1)),),
                   mass_kg=0.005, friction=0.35, shape_class="box", source="ISO/IEC 7810 ID-1 card"),
        ObjectSpec(name="cup", geoms=(_upright_cylinder(0.0375, 0.095, white),), mass_kg=0.010, friction=0.45,
                   shape_class="cylinder", source="paper cup, 75 mm x 95 mm, 10 g"),
        ObjectSpec(name="tennis_ball", geoms=(_sphere(0.0335, (0.8, 0.9, 0.2, 1)),), mass_kg=0.058, friction=0.7,
                   shape_class="sphere", source=YCB + "; felt"),
        ObjectSpec(name="golf_ball", geoms=(_sphere(0.02135, white),), mass_kg=0.0459, friction=0.3,
                   shape_class="sphere", source="R&A/USGA rules: 42.67 mm, <= 45.93 g"),
        ObjectSpec(name="apple", geoms=(_sphere(0.0375, (0.7, 0.1, 0.1, 1)),), mass_kg=0.068, friction=0.35,
                   shape_class="sphere", source=YCB + " (plastic apple)"),
        ObjectSpec(name="orange", geoms=(_sphere(0.0365, (1.0, 0.55, 0.1, 1)),), mass_kg=0.047, friction=0.5,
                   shape_class="sphere", source=YCB + " (plastic orange)"),
        ObjectSpec(name="door_handle", geoms=(
            GeomSpec(type="box", size_m=(0.02, 0.45, 1.0), pos_m=(0.02, 0, 1.0), rgba=(0.6, 0.45, 0.3, 1)),
            GeomSpec(type="cylinder", size_m=(0.0095, 0.030), pos_m=(-0.030, 0, 1.0),
                     euler_rad=(0.0, math.pi / 2, 0.0), rgba=(0.75, 0.75, 0.8, 1)),
            GeomSpec(type="cylinder", size_m=(0.0095, 0.065), pos_m=(-0.060, -0.055, 1.0),
                     euler_rad=(math.pi / 2, 0.0, 0.0), rgba=(0.75, 0.75, 0.8, 1))),
            mass_kg=0.0, friction=0.3, shape_class="fixture", free=False,
            source="lever handle, 19 mm bar, 130 mm long, 60 mm stand-off, at 1.0 m on a fixed door; "
                   "body origin on the floor, door face at x = 0, handle towards -x"),
        ObjectSpec(name="trash_can", geoms=(_upright_cylinder(0.50, 0.70, (0.3, 0.3, 0.35, 1)),), mass_kg=8.0,
                   friction=0.4, shape_class="cylinder",
                   source="50 cm radius (issue 5), 70 cm tall, 8 kg; a 2 m loop cannot encircle it"),
    ]
    return {o.name: o for o in objs}


OBJECTS: dict[str, ObjectSpec] = _catalogue()


def get_object(name: str) -> ObjectSpec:
    """Catalogue lookup; ChainModelError naming the known objects otherwise."""
    try:
        return OBJECTS[name]
    except KeyError:
        raise ChainModelError(f"object: expected one of {sorted(OBJECTS)}, got {name!r}") from None


@dataclass(frozen=True, kw_only=True)
class ObjectPlacement:
    """An object placed in the scene: body origin position (m, world) and yaw (rad)."""

    spec: ObjectSpec
    pos_m: tuple[float, float, float]
    yaw_rad: float = 0.0
