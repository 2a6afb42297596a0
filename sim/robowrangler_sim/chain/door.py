"""A door that can move: the lever handle on a leaf that swings on its hinges against a door closer.

The catalogue's ``door_handle`` (objects.py) is the handle on a fixed door. Pulled by a rope whose guide
keeps shortening it, a fixed handle is a dead end in this chain model: the rope cannot stretch and the
handle cannot give, so the shortening goes into the rope's contact with the bar until the rope passes
through it (docs/table_i.md, "door handle"). A real door gives: ``hinged_door_spec()`` is the same
handle on a leaf hinged at its far edge, held shut by a door closer, and the door scenario
(scenarios/catalogue.py) uses it.

Door frame (the body frame of the ``door_handle`` object, placed with its origin on the floor):
  * leaf: a box ``leaf_width_m`` wide (y from ``hinge_y_m`` to ``hinge_y_m + leaf_width_m``),
    ``leaf_height_m`` tall from ``leaf_bottom_m`` above the floor, ``leaf_thickness_m`` thick behind the
    face x = 0, weighing ``leaf_mass_kg``;
  * handle (rigid on the leaf, the catalogue's geometry): stand-off along -x at y = 0 (60 mm backset
    from the latch edge), 19 mm bar along y at x = -0.06 m, z = 1.0 m, its free end towards the hinges;
  * hinge ``door_handle_leaf`` (MuJoCo hinge, vertical axis at x = 0, y = ``hinge_y_m``): opening angle
    theta >= 0 turns the latch edge towards -x (a pull door); range 0 (the frame's stop) .. ``max_open_rad``.
  * closer: a spring on the hinge, closing moment M(theta) = ``closing_moment_nm`` + ``closer_stiffness
    _nm_per_rad`` x theta (MuJoCo joint stiffness with its spring reference at -M0 / k), the hinge's dry
    friction ``hinge_friction_nm`` (MuJoCo frictionloss) and the closer's hydraulic damping
    ``closer_damping_nms_per_rad``.

Numbers: an interior leaf of 0.86 m x 2.0 m x 40 mm, 25 kg (a solid-core leaf; EN 1154 power size 3
covers leaves up to 950 mm and a 60 kg test door). The closer's moment is chosen from the opening force
at the handle, the figure door hardware is specified by: 7 N m at 0 deg (+ 5 N m/rad) with 0.5 N m of hinge
friction is 9.4 N square to the leaf at the handle's 0.80 m from the hinges, a light closer well under the
30 N that BS 8300 / Approved Document M allow between 0 and 30 deg for an accessible door (a 20 N m closer,
25.6 N, is near that limit and beyond what the rope chain can hold on the bar: docs/table_i.md). The door
has no latch bolt (a closer and a roller catch, as on many pull doors): the loop pulls the lever up and
back, which turns no lever; a latched door would need the lever pressed down first. The handle's own
return spring is therefore not modelled.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import mujoco

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.objects import OBJECTS, GeomSpec, ObjectPlacement, ObjectSpec

LEAF_JOINT = "door_handle_leaf"
"""Name of the leaf's hinge joint in the MJCF (the plant's API for the door's opening angle)."""


@dataclass(frozen=True, kw_only=True)
class DoorLeaf:
    """The leaf, its hinge and its closer (SI units; see the module doc for the frame and the sources).

    Attributes:
        leaf_width_m, leaf_height_m, leaf_thickness_m: leaf size.
        leaf_bottom_m: gap under the leaf (the leaf touches nothing but the rope and the hinge).
        leaf_mass_kg: leaf mass (the handle adds 0.2 kg).
        hinge_y_m: y of the hinge axis in the door frame (the handle's stand-off is at y = 0).
        closing_moment_nm: the closer's moment with the door shut (its preload), N m.
        closer_stiffness_nm_per_rad: growth of the closer's moment with the opening angle, N m/rad.
        closer_damping_nms_per_rad: the closer's hydraulic damping, N m s/rad.
        hinge_friction_nm: dry friction of the hinges, N m.
        max_open_rad: the door stop.
    """

    leaf_width_m: float = 0.86
    leaf_height_m: float = 2.0
    leaf_thickness_m: float = 0.04
    leaf_bottom_m: float = 0.01
    leaf_mass_kg: float = 25.0
    hinge_y_m: float = -0.80
    closing_moment_nm: float = 7.0
    closer_stiffness_nm_per_rad: float = 5.0
    closer_damping_nms_per_rad: float = 5.0
    hinge_friction_nm: float = 0.5
    max_open_rad: float = 1.6

    def __post_init__(self) -> None:
        for name in ("leaf_width_m", "leaf_height_m", "leaf_thickness_m", "leaf_mass_kg", "closer_stiffness_nm_per_rad",
                     "max_open_rad"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ChainModelError(f"{name}: expected a finite value > 0, got {value!r}")
        for name in ("leaf_bottom_m", "closing_moment_nm", "closer_damping_nms_per_rad", "hinge_friction_nm"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ChainModelError(f"{name}: expected a finite value >= 0, got {value!r}")
        if not (math.isfinite(self.hinge_y_m) and -self.leaf_width_m < self.hinge_y_m < -0.12):
            raise ChainModelError(f"hinge_y_m: expected between -leaf_width_m ({-self.leaf_width_m}) and the bar's "
                                  f"free end (-0.12 m), got {self.hinge_y_m!r}")

    @property
    def latch_edge_y_m(self) -> float:
        """y of the leaf's free (latch) edge in the door frame."""
        return self.hinge_y_m + self.leaf_width_m

    def closing_moment_at_nm(self, opening_rad: float) -> float:
        """The closer's moment at an opening angle (without friction and damping), N m."""
        return self.closing_moment_nm + self.closer_stiffness_nm_per_rad * opening_rad

    def handle_force_n(self, opening_rad: float = 0.0) -> float:
        """Force at the handle's stand-off, pulled square to the leaf, that balances the closer and the hinge
        friction at opening_rad, N."""
        return (self.closing_moment_at_nm(opening_rad) + self.hinge_friction_nm) / (0.0 - self.hinge_y_m)


def hinged_door_spec(leaf: DoorLeaf | None = None) -> ObjectSpec:
    """The ``door_handle`` fixture's handle on a hinged leaf (see module doc); the leaf parameters ride in
    ``extra["door_leaf"]`` and the builder makes the hinge from them."""
    leaf = leaf if leaf is not None else DoorLeaf()
    fixed = OBJECTS["door_handle"]
    handle = fixed.geoms[1:]  # stand-off and bar, as on the fixed door
    leaf_geom = GeomSpec(type="box", size_m=(leaf.leaf_thickness_m / 2, leaf.leaf_width_m / 2, leaf.leaf_height_m / 2),
                         pos_m=(leaf.leaf_thickness_m / 2, leaf.hinge_y_m + leaf.leaf_width_m / 2,
                                leaf.leaf_bottom_m + leaf.leaf_height_m / 2),
                         rgba=fixed.geoms[0].rgba)
    return ObjectSpec(name=fixed.name, geoms=(leaf_geom,) + handle, mass_kg=0.0, friction=fixed.friction,
                      shape_class="fixture", free=False,
                      source=fixed.source.replace("on a fixed door", "on a hinged leaf with a door closer (chain/door.py)"),
                      extra={"door_leaf": leaf})


HANDLE_MASS_KG = 0.1
"""Mass of each handle part (stand-off, bar): a zinc-alloy lever is about 0.2 kg."""


def add_door_leaf(body: ET.Element, spec: ObjectSpec, *, sub, geom_attrs: dict) -> None:
    """Add the leaf (hinge, closer, leaf and handle geoms) under the door's fixed body element.

    Args:
        body: the object's MJCF body (the door frame, welded to the world).
        spec: a hinged_door_spec(); geoms are given in the door frame and moved into the leaf's frame.
        sub: the builder's element helper, sub(parent, tag, **attrs).
        geom_attrs: contact attributes every object geom gets (friction, condim, collision bits).
    """
    leaf: DoorLeaf = spec.extra["door_leaf"]
    hinge = (0.0, leaf.hinge_y_m, 0.0)
    leaf_body = sub(body, "body", name=f"{spec.name}_leafbody", pos=hinge)
    k = leaf.closer_stiffness_nm_per_rad
    sub(leaf_body, "joint", name=LEAF_JOINT, type="hinge", axis=(0, 0, 1), pos=(0, 0, 0),
        range=(0.0, leaf.max_open_rad), limited="true", stiffness=k, springref=-leaf.closing_moment_nm / k,
        damping=leaf.closer_damping_nms_per_rad, frictionloss=leaf.hinge_friction_nm)
    for i, g in enumerate(spec.geoms):
        pos = tuple(p - h for p, h in zip(g.pos_m, hinge))
        mass = leaf.leaf_mass_kg if i == 0 else HANDLE_MASS_KG
        sub(leaf_body, "geom", name=f"{spec.name}_{i}", type=g.type, size=g.size_m, pos=pos, euler=g.euler_rad,
            rgba=g.rgba, mass=mass, **geom_attrs)


def leaf_opening_rad(model: mujoco.MjModel, data: mujoco.MjData) -> float:
    """The leaf's opening angle now (0 = shut), rad."""
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, LEAF_JOINT)
    if j < 0:
        raise ChainModelError(f"model: expected a hinged door (joint {LEAF_JOINT!r}), found none")
    return float(data.qpos[model.jnt_qposadr[j]])


def door_placement(leaf: DoorLeaf | None = None) -> ObjectPlacement:
    """The hinged door with its frame origin at the world origin (door face x = 0, floor z = 0)."""
    return ObjectPlacement(spec=hinged_door_spec(leaf), pos_m=(0.0, 0.0, 0.0))
