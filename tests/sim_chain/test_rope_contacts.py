"""ChainPlant.rope_contacts: how the rope meets an object, read from MuJoCo's contacts.

Two grasps at plant level show the two cases docs/chain_model.md ("The credit card") contrasts: the mug's
wall meets the rope level with its axis and holds it with friction to spare; the 0.76 mm card's edge is
below the rope's 1 mm axis, the rope slides along it with its friction used up, and the edge lifts it on.
A model change that catches the card changes the second test on purpose, and that section of the doc with it.
"""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.grasp import GraspScript, grasp_scene, run_grasp
from robowrangler_sim.chain.params import ChainParams

ON_TOP_DEG = 60.0  # a normal this far below horizontal: the rope lies on the object


def _contacts(default_table, name, phases):
    """(time_s, contact) of every rope contact with the object in the scripted grasp's phases, every step."""
    params = ChainParams()
    seen = []

    def on_sample(plant, phase):
        if phase in phases:
            seen.extend((plant.time_s, c) for c in plant.rope_contacts(name))

    run_grasp(name, table=default_table, params=params, sample_s=params.timestep_s, on_sample=on_sample)
    return seen


def test_a_wall_level_with_the_rope_holds_it_with_friction_to_spare(default_table):
    seen = _contacts(default_table, "mug", ("retract", "hold", "pull"))
    loaded = [c for _, c in seen if c.normal_force_n > 1e-3]
    assert len(loaded) > 100
    tilt = np.array([c.normal_tilt_deg for c in loaded])
    assert np.all(np.abs(tilt) < 5.0), tilt                           # the wall pushes the rope sideways
    assert np.median([c.friction_use for c in loaded]) < 0.5          # friction is not what holds it
    assert max(c.normal_force_n for c in loaded) > 0.1                # the rope drags a 0.3 kg mug
    assert all(0 <= c.link_index < ChainParams().n_links for c in loaded)


def test_a_card_edge_below_the_rope_axis_lifts_the_sliding_rope_onto_it(default_table):
    seen = _contacts(default_table, "credit_card", ("retract",))
    assert seen, "the retracting loop never reached the card"
    _, first = seen[0]
    # the card's top edge (0.76 mm) meets the rope (axis 1 mm up) below its axis: a ramp of 10-25 deg
    assert 10.0 < first.normal_tilt_deg < 25.0, first
    on_top = [t for t, c in seen if c.normal_tilt_deg > ON_TOP_DEG]
    assert on_top, "the rope never rode onto the card"
    against_edge = [c for t, c in seen if t < on_top[0] and c.normal_force_n > 1e-4]
    assert against_edge
    # while against the edge the rope slides with its friction used up, and presses with about a mN,
    # far less than the 29 mN that would slide the 5 g card
    assert np.median([c.friction_use for c in against_edge]) > 0.8
    assert max(c.normal_force_n for c in against_edge) < 0.01
    assert np.median([abs(c.slip_along_rope_mps) for c in against_edge]) > 1e-3


def test_contacts_of_an_unknown_object_are_a_typed_error(default_table):
    plant, _ = grasp_scene("mug", table=default_table, params=ChainParams(), script=GraspScript())
    assert plant.rope_contacts("mug") == []                           # the airborne loop touches nothing
    with pytest.raises(ChainModelError, match="mug"):
        plant.rope_contacts("teapot")
