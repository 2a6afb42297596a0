"""The MJCF builder: chain size, joints, drives, closure, parameters and their validation."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robowrangler_sim.chain.builder import build_chain_model
from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.params import ChainParams


@pytest.mark.parametrize("n_links", [10, 20, 40])
def test_model_builds_with_two_hinges_per_link_and_drives_on_the_upper_branch(n_links):
    p = ChainParams(n_links=n_links)
    m = build_chain_model(p)
    assert m.njnt == 2 * n_links + 3 and m.nv == 2 * n_links + 3  # + the module's three slides
    axes = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j): m.jnt_axis[j] for j in range(m.njnt)}
    for i in range(n_links):
        np.testing.assert_allclose(axes[f"inplane_{i}"], [0, -1, 0])
        np.testing.assert_allclose(axes[f"outplane_{i}"], [0, 0, 1])
    assert m.nu == p.n_upper == n_links // 2
    np.testing.assert_allclose(m.actuator_gainprm[:, 0], 1.0e4)
    np.testing.assert_allclose(m.actuator_biasprm[:, 1:3], [[-1.0e4, -5.0e3]] * m.nu)
    driven = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, m.actuator_trnid[a, 0]) for a in range(m.nu)}
    assert driven == {f"inplane_{i}" for i in range(n_links // 2)}
    assert m.ntendon == 1 and m.tendon_stiffness[0] == p.closure_stiffness_n_per_m
    link_masses = [m.body_mass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"link_{i}")] for i in range(n_links)]
    np.testing.assert_allclose(sum(link_masses), 2.21e-4 * 2.0, rtol=1e-6)
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


def test_default_link_weighs_about_2e_5_kg():
    assert ChainParams().link_mass_kg == pytest.approx(2.2e-5, rel=0.01)


@pytest.mark.parametrize("kwargs, field", [
    (dict(n_links=9), "n_links"), (dict(n_links=81), "n_links"), (dict(n_links=20.0), "n_links"),
    (dict(timestep_s=0.0), "timestep_s"), (dict(kp_upper_nm_per_rad=-1.0), "kp_upper_nm_per_rad"),
    (dict(rope_length_m=float("nan")), "rope_length_m"), (dict(upper_branch_fraction=1.0), "upper_branch_fraction"),
    (dict(rope_length_m=0.5), "rope_length_m"),
])
def test_bad_parameters_raise_a_typed_error_naming_the_field(kwargs, field):
    with pytest.raises(ChainModelError, match=field):
        ChainParams(**kwargs)


def test_loop_length_is_rope_minus_what_the_guide_keeps_inside():
    p = ChainParams()
    assert p.loop_length_m(0.0) == pytest.approx(2.0)
    assert p.loop_length_m(180.0) == pytest.approx(2.0 - 2.0 * 0.18)
    with pytest.raises(ChainModelError, match="guide_position_mm"):
        p.loop_length_m(181.0)
