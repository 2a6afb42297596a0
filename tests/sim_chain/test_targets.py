"""Shape table -> joint targets: the chain laid on the targets reproduces the contour."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robowrangler_sim.chain.accuracy import point_to_polyline_m
from robowrangler_sim.chain.targets import ShapeTargets, chain_points_from_targets


@pytest.mark.parametrize("phi_deg", [-30.0, -12.5, 0.0, 17.3, 40.0])
def test_forward_kinematics_of_the_targets_lies_on_the_contour(table, phi_deg):
    targets = ShapeTargets(table, n_links=20)
    q = targets.joint_targets(math.radians(phi_deg))
    pts = chain_points_from_targets(q, link_length_m=table.loop_length_m / 20, phi_rad=math.radians(phi_deg))
    assert np.max(point_to_polyline_m(pts, table.contour(phi_deg))) < 0.01
    ret = targets.return_point_per_m(math.radians(phi_deg)) * table.loop_length_m
    c, s = math.cos(math.radians(phi_deg)), math.sin(math.radians(phi_deg))
    np.testing.assert_allclose([c * ret[0] - s * ret[1], s * ret[0] + c * ret[1]], table.contour(phi_deg)[-1],
                               atol=1e-3)


def test_targets_change_smoothly_with_phi_and_clamp_outside_the_table(table):
    targets = ShapeTargets(table, n_links=20)
    a = targets.joint_targets(math.radians(10.0))
    b = targets.joint_targets(math.radians(10.05))
    assert np.max(np.abs(a - b)) < 2e-3
    np.testing.assert_allclose(targets.joint_targets(math.radians(60.0)), targets.joint_targets(math.radians(40.0)))
