"""The rope lying flat on the floor: it rests on it (no clearance), the module drags it with a real velocity,
and the low Table I objects (tuna can 33 mm, sponge 14 mm) are caught and dragged, not ridden over.

docs/chain_model.md, "Rope on the floor and the moving module", says why each piece is needed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robowrangler_sim.chain.grasp import GraspScript, grasp_inputs, grasp_scene, run_grasp
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz


def test_relaxed_rope_rests_on_the_floor(default_table):
    params = ChainParams()
    script = GraspScript()
    plant, base = grasp_scene("mug", table=default_table, params=params, script=script)
    while plant.time_s < script.position_s + script.relax_s:
        plant.step(grasp_inputs(script, plant.time_s, base_pos_m=base)[1])
    # links away from the exit (which is exit_height_m up) lie on the floor: axis at the rope radius
    # (1 mm), within the contact's penetration; with the old 10 mm contact margin they floated at 11 mm
    z_mid_m = 0.5 * (plant.chain_points_m()[:-1, 2] + plant.chain_points_m()[1:, 2])
    lying = z_mid_m[3:-3]
    assert np.all(lying < params.rope_radius_m + 0.5e-3), lying
    assert np.all(lying > params.rope_radius_m - 0.7e-3), lying


@pytest.mark.parametrize("name", ["tuna_can", "sponge"])
def test_low_objects_are_caught_and_dragged(default_table, name):
    out = run_grasp(name, table=default_table)
    assert out.secured, (f"{name}: follow {out.follow_ratio:.2f}, rope touching {out.touching_fraction:.0%}, "
                         f"mean rope force {out.mean_pull_force_n:.3f} N")
    assert out.object_displacement_m[0] < -0.1          # dragged towards the module
    assert abs(out.object_displacement_m[2]) < 2e-3     # on the floor: the rope did not go under it
    assert out.touching_fraction >= 0.8 and out.mean_pull_force_n > 0.02


def test_module_moves_with_a_real_velocity_and_jumps_are_replacements(table):
    params = ChainParams()
    quat = pitch_quat_wxyz(0.0)
    start = np.array([0.0, 0.0, 1.0])
    plant = ChainPlant(table=table, params=params, initial=PlantInputs(rope_speed_mps=5.0, base_pos_m=tuple(start),
                                                                       base_quat_wxyz=quat))
    speed_mps = 0.2
    for k in range(1, 41):  # 0.2 m/s along -x, commanded at every step
        pos = start + np.array([-speed_mps * k * params.timestep_s, 0.0, 0.0])
        plant.step(PlantInputs(rope_speed_mps=5.0, base_pos_m=tuple(pos), base_quat_wxyz=quat))
        # the velocity the solver saw during the step is the commanded motion, and the module got there
        np.testing.assert_allclose(plant.module_velocity_mps(), [-speed_mps, 0.0, 0.0], atol=1e-3)
        np.testing.assert_allclose(plant.module_pos_m(), pos, atol=1e-5)
    # a jump farther than module_max_step_m is a re-placement, at rest
    far = start + np.array([0.0, 0.0, 0.5])
    plant.step(PlantInputs(rope_speed_mps=5.0, base_pos_m=tuple(far), base_quat_wxyz=quat))
    np.testing.assert_allclose(plant.module_pos_m(), far, atol=1e-5)
    assert np.linalg.norm(plant.module_velocity_mps()) < 1e-3
    # the orientation is set directly (the inclination that selects the shape)
    tilted = pitch_quat_wxyz(math.radians(0.5))
    plant.step(PlantInputs(rope_speed_mps=5.0, base_pos_m=tuple(far), base_quat_wxyz=tilted))
    np.testing.assert_allclose(plant.module_quat_wxyz(), tilted, atol=1e-5)
