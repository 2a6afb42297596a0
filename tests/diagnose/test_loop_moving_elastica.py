"""The running rope's Euler-Bernoulli balance behind tip_bending_stiffness (diagnose/loop/moving_elastica.py), checked
against the first-principles string shooter."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robowrangler_sim.diagnose.loop.moving_elastica import bending_displacement_m, effective_tension_n
from robowrangler_sim.shape_table import resample_by_arc_length
from robowrangler_sim.string_shooter.model import StringShooter
from robowrangler_sim.string_shooter.motion import ModuleMotion
from robowrangler_sim.string_shooter.params import ShooterParams


def _steady(bending_factor: float, speed_mps: float, phi_rad: float):
    base = ShooterParams()
    rope = dataclasses.replace(base.rope, bending_stiffness_n_m2=base.rope.bending_stiffness_n_m2 * bending_factor)
    motion = ModuleMotion(wheel_speed_mps=lambda t: speed_mps + 0.0 * np.asarray(t),
                          phi_rad=lambda t: phi_rad + 0.0 * np.asarray(t))
    sh = StringShooter(dataclasses.replace(base, rope=rope), loop_length_m=2.0, motion=motion, initial_shape="circle")
    sh.step_for(3.0)
    pts = []
    for _ in range(15):
        sh.step_for(1.0 / 30.0)
        pts.append(resample_by_arc_length(sh.frame().loop_plane_xz_m(), 40))
    return np.mean(pts, axis=0), sh.segment_tensions_n(), base.rope


@pytest.fixture(scope="module")
def loops():
    return {f: _steady(f, 4.0, 0.0) for f in (1.0, 20.0)}


def test_the_force_balance_of_the_contour_gives_the_string_shooters_tension(loops):
    contour, tension, rope = loops[1.0]
    _, te = effective_tension_n(contour, speed_mps=4.0, rope=rope)
    lam_v2 = rope.linear_density_kg_per_m * 16.0
    # compressed at the exit (the nip pushes the rope out), pulled at the return
    assert te[0] < -2e-3 < 2e-3 < te[-1]
    assert te[0] == pytest.approx(tension[0] - lam_v2, abs=5e-4)
    assert te[-1] == pytest.approx(tension[-1] - lam_v2, abs=5e-4)


def test_the_law_moves_the_table_rope_toward_the_stiff_rope_and_is_neutral_at_b0(loops):
    c0, _, rope = loops[1.0]
    c20 = loops[20.0][0]
    assert np.all(bending_displacement_m(c0, speed_mps=4.0, bending_stiffness_n_m2=rope.bending_stiffness_n_m2,
                                         rope=rope) == 0.0)
    moved = c0 + bending_displacement_m(c0, speed_mps=4.0, bending_stiffness_n_m2=20.0 * rope.bending_stiffness_n_m2,
                                        rope=rope)

    def rms(a, b):
        return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))

    assert rms(c20, c0) > 0.015  # the stiff rope's loop differs from the table rope's by more than the camera noise
    assert rms(c20, moved) < 0.6 * rms(c20, c0)
    np.testing.assert_allclose(moved[[0, -1]], c0[[0, -1]], atol=1e-3)  # exit and return points held


def test_bad_input_is_named(loops):
    c0, _, rope = loops[1.0]
    with pytest.raises(ValueError, match="bending_stiffness_n_m2"):
        bending_displacement_m(c0, speed_mps=4.0, bending_stiffness_n_m2=-1.0, rope=rope)
    with pytest.raises(ValueError, match="contour_m"):
        bending_displacement_m(c0[:2], speed_mps=4.0, bending_stiffness_n_m2=1e-5, rope=rope)
