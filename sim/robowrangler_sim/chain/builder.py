"""MJCF of the rope-loop chain, built in code from ChainParams (every number comes from a parameter).

Tree (names are the plant's API)::

    world
      floor                      optional plane at floor_height_m (contype 8)
      module_carriage            slide joints module_x/y/z (world axes): the module's position, motion
                                 prescribed by the plant (the robot's leg), with a real velocity
        module                   the manipulator base, orientation set by the plant;
                                 its frame: x = launch axis, z = up, y = loop normal
        module_housing (geom)    box behind the exit (contacts objects, not the chain)
        exit, return (sites)     guide exit (origin) and return point of the loop
        link_0                   joints inplane_0 (axis -y), outplane_0 (axis z); capsule geom link_0
          link_0_end (site)
          link_1 ...             each link joined to the previous by the same two hinges
      <object> bodies            free (freejoint <name>_free) or fixtures

    tendon  closure              spatial tendon link_{N-1}_end -> return, spring rest length 0
    equality closure_constraint  (when closure_constraint_timeconst_s > 0) soft connect of the same
                                 two points: the spring made implicit by the constraint solver
    actuators drive_inplane_<i>, drive_outplane_<i>: general position servos (gain kp, bias -kp q - kd qdot)
            only where the parameter gains are non-zero.

Collision bits: chain 1, objects 2, module 4, floor 8. The chain touches objects and floor only
(no self-contact: the paper's chain has none, and it costs time), objects touch everything.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.objects import ObjectPlacement
from robowrangler_sim.chain.params import ChainParams

CHAIN_BITS = dict(contype=1, conaffinity=2)  # chain-floor contacts are explicit pairs (clearance margin)
OBJECT_BITS = dict(contype=2, conaffinity=1 | 2 | 4 | 8)
MODULE_BITS = dict(contype=4, conaffinity=2)
FLOOR_BITS = dict(contype=8, conaffinity=1 | 2)

MODULE_HOUSING_HALF_M = (0.06, 0.04, 0.04)


def _f(*values: float) -> str:
    return " ".join(f"{float(v):.9g}" for v in values)


def _sub(parent: ET.Element, tag: str, **attrs) -> ET.Element:
    el = ET.SubElement(parent, tag)
    for k, v in attrs.items():
        if v is None:
            continue
        if isinstance(v, dict):
            raise TypeError(k)
        el.set(k, v if isinstance(v, str) else _f(*np.atleast_1d(v)))
    return el


def _bits(d: dict) -> dict:
    return {k: str(v) for k, v in d.items()}


def build_chain_mjcf(params: ChainParams, *, objects: tuple[ObjectPlacement, ...] = (),
                     floor_height_m: float | None = None,
                     module_pos_m: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> str:
    """MJCF text of the chain (at the home loop length, straight along +x), module, floor and objects.

    Args:
        params: the chain parameters.
        objects: objects placed in the scene.
        floor_height_m: z of a floor/table plane, or None for no floor.
        module_pos_m: initial module position, world frame, metres.
    Returns: MJCF XML string.
    """
    n = params.n_links
    link_len = params.home_loop_length_m / n
    r = params.rope_radius_m
    root = ET.Element("mujoco", model=f"robowrangler_chain_{n}")
    _sub(root, "compiler", angle="radian", autolimits="true")
    _sub(root, "option", timestep=params.timestep_s, integrator="implicitfast", gravity=(0, 0, -9.81))
    size = _sub(root, "size")
    size.set("memory", "8M")
    visual = _sub(root, "visual")
    _sub(visual, "global", offwidth="1280", offheight="720")
    _sub(visual, "quality", shadowsize="2048")
    asset = _sub(root, "asset")
    _sub(asset, "texture", name="grid", type="2d", builtin="checker", rgb1=(0.82, 0.82, 0.80),
         rgb2=(0.70, 0.70, 0.68), width="256", height="256")
    _sub(asset, "material", name="grid", texture="grid", texrepeat=(8, 8), reflectance=0.05)
    _sub(asset, "texture", name="sky", type="skybox", builtin="gradient", rgb1=(0.55, 0.7, 0.9),
         rgb2=(0.95, 0.95, 1.0), width="256", height="256")

    rope_solimp = (params.contact_impedance_min, params.contact_impedance_max, params.contact_impedance_width_m,
                   0.5, 2)
    world = _sub(root, "worldbody")
    _sub(world, "light", name="sun", pos=(0.5, -1.0, 4.0), dir=(-0.1, 0.25, -1), diffuse=(0.8, 0.8, 0.8),
         directional="true")
    if floor_height_m is not None:
        if not math.isfinite(floor_height_m):
            raise ChainModelError(f"floor_height_m: expected a finite height or None, got {floor_height_m}")
        _sub(world, "geom", name="floor", type="plane", size=(10, 10, 0.1), pos=(0, 0, floor_height_m),
             material="grid", friction=(params.floor_friction, 0.005, 0.0001), **_bits(FLOOR_BITS))

    # the module translates on three world-aligned slide joints whose motion the plant prescribes (velocity
    # set each step): unlike a mocap body it has a real velocity, which the contact solver sees; its
    # orientation is the child body's quaternion, set by the plant (docs/chain_model.md, "Rope on the floor")
    carriage = _sub(world, "body", name="module_carriage", pos=module_pos_m, gravcomp="1")
    for axis, vec in (("x", (1, 0, 0)), ("y", (0, 1, 0)), ("z", (0, 0, 1))):
        _sub(carriage, "joint", name=f"module_{axis}", type="slide", axis=vec)
    _sub(carriage, "inertial", pos=(0, 0, 0), mass=params.module_mass_kg, diaginertia=(1e-3, 1e-3, 1e-3))
    module = _sub(carriage, "body", name="module", pos=(0, 0, 0))
    hx, hy, hz = MODULE_HOUSING_HALF_M
    _sub(module, "geom", name="module_housing", type="box", size=(hx, hy, hz), pos=(-hx, 0, -0.01),
         rgba=(0.25, 0.27, 0.3, 1), mass="0", friction=(0.5, 0.005, 0.0001), **_bits(MODULE_BITS))
    _sub(module, "site", name="exit", pos=(0, 0, 0), size=(0.004,), rgba=(0, 1, 0, 1))
    _sub(module, "site", name="return", pos=(0, 0, -0.02), size=(0.004,), rgba=(1, 0, 0, 1))

    parent = module
    for i in range(n):
        body = _sub(parent, "body", name=f"link_{i}", pos=(0, 0, 0) if i == 0 else (link_len, 0, 0))
        common = dict(type="hinge", pos=(0, 0, 0), armature=params.armature_kgm2)
        _sub(body, "joint", name=f"inplane_{i}", axis=(0, -1, 0), damping=params.passive_damping_nms_per_rad,
             **common)
        _sub(body, "joint", name=f"outplane_{i}", axis=(0, 0, 1),
             damping=params.out_of_plane_damping_nms_per_rad, **common)
        upper = i < params.n_upper
        _sub(body, "geom", name=f"link_{i}", type="capsule", size=(r, link_len / 2), pos=(link_len / 2, 0, 0),
             euler=(0, math.pi / 2, 0), mass=params.link_mass_kg, solimp=rope_solimp, solmix="1000",
             rgba=(0.95, 0.45, 0.1, 1) if upper else (0.95, 0.75, 0.2, 1),
             friction=(params.rope_friction, 0.005, 0.0001), **_bits(CHAIN_BITS))
        _sub(body, "geom", name=f"link_{i}_visual", type="capsule", size=(params.visual_rope_radius_m, link_len / 2),
             pos=(link_len / 2, 0, 0), euler=(0, math.pi / 2, 0), mass="0", contype="0", conaffinity="0",
             group="1", rgba=(0.95, 0.45, 0.1, 1) if upper else (0.95, 0.75, 0.2, 1))
        _sub(body, "site", name=f"link_{i}_end", pos=(link_len, 0, 0), size=(r,))
        parent = body

    for placement in objects:
        _add_object(world, placement)

    tendon = _sub(root, "tendon")
    spatial = _sub(tendon, "spatial", name="closure", stiffness=params.closure_stiffness_n_per_m,
                   damping=params.closure_damping_ns_per_m, springlength=(0.0,), width=r / 2,
                   rgba=(0.2, 0.6, 1, 0.6))
    _sub(spatial, "site", site=f"link_{n - 1}_end")
    _sub(spatial, "site", site="return")
    if floor_height_m is not None:
        contact = _sub(root, "contact")
        for i in range(n):
            _sub(contact, "pair", geom1="floor", geom2=f"link_{i}", condim="3", solimp=rope_solimp,
                 margin=params.rope_floor_clearance_m, friction=(params.floor_friction, params.floor_friction,
                                                                 0.005, 0.0001, 0.0001))
    if params.closure_constraint_timeconst_s > 0:
        equality = _sub(root, "equality")
        _sub(equality, "connect", name="closure_constraint", body1=f"link_{n - 1}", body2="module",
             anchor=(link_len, 0, 0), solref=(params.closure_constraint_timeconst_s, 1.0))

    actuator = _sub(root, "actuator")
    for i in range(n):
        upper = i < params.n_upper
        kp = params.kp_upper_nm_per_rad if upper else params.kp_lower_nm_per_rad
        kd = params.kd_upper_nms_per_rad if upper else params.kd_lower_nms_per_rad
        if kp > 0 or kd > 0:
            _sub(actuator, "general", name=f"drive_inplane_{i}", joint=f"inplane_{i}", gaintype="fixed",
                 biastype="affine", gainprm=(kp,), biasprm=(0, -kp, -kd), ctrlrange=(-math.pi, math.pi), ctrllimited="false")
    kp, kd = params.kp_out_of_plane_nm_per_rad, params.kd_out_of_plane_nms_per_rad
    if kp > 0 or kd > 0:
        for i in range(n):
            _sub(actuator, "general", name=f"drive_outplane_{i}", joint=f"outplane_{i}", gaintype="fixed",
                 biastype="affine", gainprm=(kp,), biasprm=(0, -kp, -kd), ctrllimited="false")
    return ET.tostring(root, encoding="unicode")


def _add_object(world: ET.Element, placement: ObjectPlacement) -> None:
    spec = placement.spec
    x, y, z = placement.pos_m
    if not all(math.isfinite(v) for v in (x, y, z, placement.yaw_rad)):
        raise ChainModelError(f"pos_m/yaw_rad of {spec.name}: expected finite numbers, got "
                              f"{placement.pos_m}, {placement.yaw_rad}")
    body = _sub(world, "body", name=spec.name, pos=(x, y, z), euler=(0, 0, placement.yaw_rad))
    if spec.extra.get("door_leaf") is not None:  # the door on its hinges (chain/door.py)
        from robowrangler_sim.chain.door import add_door_leaf

        add_door_leaf(body, spec, sub=_sub, geom_attrs=dict(friction=(spec.friction, 0.005, 0.0001), condim="4",
                                                            **_bits(OBJECT_BITS)))
        return
    if spec.free:
        _sub(body, "freejoint", name=f"{spec.name}_free")
    masses = spec.geom_masses_kg() if spec.free else [None] * len(spec.geoms)
    for k, (g, mass) in enumerate(zip(spec.geoms, masses)):
        _sub(body, "geom", name=f"{spec.name}_{k}", type=g.type, size=g.size_m, pos=g.pos_m, euler=g.euler_rad,
             rgba=g.rgba, mass=mass, friction=(spec.friction, 0.005, 0.0001), condim="4",
             **_bits(OBJECT_BITS))


def build_chain_model(params: ChainParams, **kwargs) -> mujoco.MjModel:
    """Compile the MJCF of build_chain_mjcf (same keyword options) into an MjModel."""
    return mujoco.MjModel.from_xml_string(build_chain_mjcf(params, **kwargs))
