"""Objects: catalogue after the paper's Table I, real masses in the model, resting stably on a floor."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.objects import OBJECTS, GeomSpec, ObjectPlacement, ObjectSpec, get_object
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs

TABLE_I = ["chips_can", "tuna_can", "banana", "sponge", "mug", "marker", "screwdriver", "credit_card", "cup",
           "tennis_ball", "golf_ball", "apple", "orange"]


def test_catalogue_has_table_i_objects_door_handle_and_trash_can():
    assert set(TABLE_I) | {"door_handle", "trash_can"} == set(OBJECTS)
    assert get_object("trash_can").geoms[0].size_m[0] == pytest.approx(0.5)
    assert get_object("tennis_ball").expected_outcome == "slips"
    assert get_object("chips_can").expected_outcome == "secured"
    assert get_object("mug").expected_outcome == "secured"
    with pytest.raises(ChainModelError, match="object"):
        get_object("anvil")


def test_bad_object_specs_raise_typed_errors():
    with pytest.raises(ChainModelError, match="size_m"):
        GeomSpec(type="sphere", size_m=(0.1, 0.2))
    with pytest.raises(ChainModelError, match="mass_kg"):
        ObjectSpec(name="x", geoms=(GeomSpec(type="sphere", size_m=(0.1,)),), mass_kg=0.0, friction=0.5,
                   shape_class="sphere")


def test_every_object_has_its_mass_and_rests_on_the_floor(table):
    placements = tuple(ObjectPlacement(spec=OBJECTS[name], pos_m=(1.0 + 0.4 * k, -1.5, 0.0))
                       for k, name in enumerate(TABLE_I))
    plant = ChainPlant(table=table, objects=placements, floor_height_m=0.0,
                       initial=PlantInputs(rope_speed_mps=5.0, base_pos_m=(0.0, 0.0, 1.0)))
    m = plant.model
    for name in TABLE_I:
        bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        assert m.body_mass[bid] == pytest.approx(OBJECTS[name].mass_kg, rel=1e-6)
    start = {n: plant.object_pos_m(n) for n in TABLE_I}
    plant.advance(duration_s=1.0)
    for name in TABLE_I:
        moved = np.linalg.norm(plant.object_pos_m(name) - start[name])
        assert moved < 0.01, f"{name} moved {moved:.3f} m resting on the floor"
        assert math.isclose(np.linalg.norm(plant.object_quat_wxyz(name)), 1.0, rel_tol=1e-9)


def test_trash_can_rests_and_door_handle_is_a_fixed_fixture(table):
    placements = (ObjectPlacement(spec=OBJECTS["trash_can"], pos_m=(1.5, 0.0, 0.0)),
                  ObjectPlacement(spec=OBJECTS["door_handle"], pos_m=(3.0, 0.06, 0.0)))
    plant = ChainPlant(table=table, objects=placements, floor_height_m=0.0,
                       initial=PlantInputs(rope_speed_mps=5.0, base_pos_m=(0.0, 0.0, 1.0)))
    m = plant.model
    assert m.body_mass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "trash_can")] == pytest.approx(8.0)
    handle = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "door_handle")
    assert m.body_jntnum[handle] == 0  # welded to the world
    start = plant.object_pos_m("trash_can")
    plant.advance(duration_s=1.0)
    assert np.linalg.norm(plant.object_pos_m("trash_can") - start) < 0.005
    np.testing.assert_allclose(plant.object_pos_m("door_handle"), [3.0, 0.06, 0.0])
    assert plant.outputs().object_secured == {"trash_can": False}
