"""The hinged door (chain/door.py): its closer holds the leaf shut against the frame's stop until the force at
the handle beats the closer's moment; real MuJoCo, no rope."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from robowrangler_sim.chain.builder import build_chain_model
from robowrangler_sim.chain.door import DoorLeaf, door_placement, hinged_door_spec, leaf_opening_rad
from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.params import ChainParams

BAR_POS_M = np.array([-0.06, -0.08, 1.0])  # where the loop pulls: on the bar, 8 cm from the stand-off


def _door_model() -> mujoco.MjModel:
    # the module and its (straight, resting) chain far from the door: nothing touches the leaf but the test
    return build_chain_model(ChainParams(n_links=10, timestep_s=0.002), objects=(door_placement(LEAF),),
                             module_pos_m=(-3.0, 3.0, 1.0))


LEAF = DoorLeaf(closing_moment_nm=7.0)


def _opening_after_pull_deg(force_n: float, *, duration_s: float = 1.0) -> float:
    """Pull the bar along -x (square to the shut leaf) with force_n for duration_s; the leaf's opening angle."""
    model = _door_model()
    data = mujoco.MjData(model)
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "door_handle_leafbody")
    for _ in range(round(duration_s / model.opt.timestep)):
        data.xfrc_applied[:] = 0.0
        mujoco.mj_applyFT(model, data, np.array([-force_n, 0.0, 0.0]), np.zeros(3), BAR_POS_M, body,
                          data.qfrc_applied)
        mujoco.mj_step(model, data)
        data.qfrc_applied[:] = 0.0
    return math.degrees(leaf_opening_rad(model, data))


def test_the_closer_keeps_the_door_shut_until_the_handle_force_beats_it() -> None:
    leaf = LEAF
    # square to the leaf at the handle: (7 N m + 0.5 N m friction) / 0.80 m = 9.4 N; the bar is 8 cm nearer the
    # hinges (0.72 m), so the pull needs 10.4 N there
    assert leaf.handle_force_n() == pytest.approx(7.5 / 0.8)
    assert _opening_after_pull_deg(0.0) == pytest.approx(0.0, abs=0.05)
    assert _opening_after_pull_deg(9.5) < 0.2
    opened = _opening_after_pull_deg(16.0)
    assert opened > 5.0
    # the closer pulls it back shut when the pull stops
    model = _door_model()
    data = mujoco.MjData(model)
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "door_handle_leaf")
    data.qpos[model.jnt_qposadr[j]] = math.radians(20.0)
    for _ in range(2000):
        mujoco.mj_step(model, data)
    assert math.degrees(leaf_opening_rad(model, data)) < 1.0


def test_door_spec_keeps_the_handle_geometry_and_rejects_bad_numbers() -> None:
    spec = hinged_door_spec(DoorLeaf())
    from robowrangler_sim.chain.objects import OBJECTS

    assert spec.geoms[1:] == OBJECTS["door_handle"].geoms[1:] and spec.name == "door_handle" and not spec.free
    with pytest.raises(ChainModelError, match="closing_moment_nm: expected a finite value >= 0"):
        DoorLeaf(closing_moment_nm=-1.0)
    with pytest.raises(ChainModelError, match="hinge_y_m: expected between"):
        DoorLeaf(hinge_y_m=0.0)
