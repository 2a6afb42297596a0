"""The chain model's objects become the same static shapes for the string shooter (checked against
MuJoCo's own geometry), and the rope touches them."""

import mujoco
import numpy as np
import pytest

from robowrangler_sim.chain.objects import OBJECTS, ObjectPlacement, get_object
from robowrangler_sim.string_shooter import ModuleMotion, ShooterParams, StringShooter
from robowrangler_sim.string_shooter.chain_objects import euler_xyz_intrinsic, obstacles_for_placement
from robowrangler_sim.string_shooter.contact import signed_distance_m


def test_euler_convention_matches_mujoco():
    euler = (0.3, -0.7, 1.1)
    model = mujoco.MjModel.from_xml_string(
        f'<mujoco><compiler angle="radian"/><worldbody><geom type="box" size=".1 .2 .3" euler="{euler[0]} {euler[1]} {euler[2]}"/>'
        "</worldbody></mujoco>")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert np.allclose(data.geom_xmat[0].reshape(3, 3), euler_xyz_intrinsic(euler), atol=1e-9)


@pytest.mark.parametrize("name", sorted(OBJECTS))  # every object of the chain model's catalogue
def test_object_surface_agrees_with_mujoco(name):
    """Points on each MuJoCo geom's surface (found by ray casting) lie on our obstacle surface."""
    placement = ObjectPlacement(spec=get_object(name), pos_m=(0.4, -0.1, 0.0), yaw_rad=0.5)
    obstacles = obstacles_for_placement(placement)
    spec = placement.spec
    parts = []
    for i, g in enumerate(spec.geoms):
        size = " ".join(str(s) for s in g.size_m)
        parts.append(f'<geom name="g{i}" type="{g.type}" size="{size}" pos="{" ".join(map(str, g.pos_m))}" '
                     f'euler="{" ".join(map(str, g.euler_rad))}"/>')
    xml = (f'<mujoco><compiler angle="radian"/><worldbody><body pos="{" ".join(map(str, placement.pos_m))}" euler="0 0 {placement.yaw_rad}">'
           + "".join(parts) + "</body></worldbody></mujoco>")
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(0)
    geomid = np.zeros(1, dtype=np.int32)
    for i, ob in enumerate(obstacles):
        center = data.geom_xpos[i]
        hits = 0
        for _ in range(40):
            direction = rng.standard_normal(3)
            direction /= np.linalg.norm(direction)
            start = center + direction * 2.0  # from outside, toward the geom centre
            dist = mujoco.mj_ray(model, data, start, -direction, None, 1, -1, geomid)
            if dist < 0 or geomid[0] != i:
                continue
            hit = start - direction * dist
            assert signed_distance_m(ob, hit[None])[0] == pytest.approx(0.0, abs=1e-6)
            hits += 1
        assert hits > 10


def test_a_loop_dropped_on_the_door_handle_hangs_on_it():
    # door parallel to the loop plane 6 cm behind it, the handle bar across the plane 30 cm below the eyelet
    placement = ObjectPlacement(spec=get_object("door_handle"), pos_m=(0.05, 0.06, -1.3), yaw_rad=np.pi / 2)
    obstacles = obstacles_for_placement(placement)
    sim = StringShooter(ShooterParams(), loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=0.5),
                        obstacles=obstacles)
    sim.step_for(1.5)
    pts = sim.frame().points_m
    d = np.min([signed_distance_m(ob, pts) for ob in obstacles], axis=0)
    assert d.min() > -1e-3
    bar = obstacles[2]  # the handle bar (door, stand-off, bar)
    assert signed_distance_m(bar, pts).min() < 0.005  # resting on the handle bar
