"""Loop shape versus inclination (the paper's Fig. 5b): elongated at negative phi, rounder at positive."""

import numpy as np
import pytest

from robowrangler_sim.shape_table import ShapeTable
from robowrangler_sim.string_shooter import ShooterParams
from robowrangler_sim.string_shooter.shape import roundness
from robowrangler_sim.string_shooter.shape_export import DEFAULT_TABLE_PATH, steady_contour_xz_m


@pytest.fixture(scope="module")
def roundness_by_phi():
    return {phi: roundness(steady_contour_xz_m(ShooterParams(), phi_deg=phi, rope_speed_mps=5.0, loop_length_m=1.0,
                                               n_points=60, settle_s=3.0))
            for phi in (-30.0, 0.0, 20.0)}


def test_loop_is_elongated_at_negative_phi_and_rounder_at_positive_phi(roundness_by_phi):
    r = roundness_by_phi
    assert r[-30.0] < r[0.0] < r[20.0]
    assert r[20.0] / r[-30.0] > 1.2


def test_default_shape_table_loads_and_covers_the_paper_range():
    table = ShapeTable.load(DEFAULT_TABLE_PATH)
    assert table.phi_deg.tolist() == list(range(-30, 41, 5))
    assert 5.0 in table.rope_speed_mps.tolist()
    assert table.loop_length_m == 2.0
    c = table.contours_m
    assert np.allclose(c[:, :, 0], 0.0)  # every contour starts at the exit
    spacing = np.linalg.norm(np.diff(c, axis=2), axis=3)
    median = np.median(spacing, axis=2, keepdims=True)
    # equally spaced along the rope: chords equal the spacing except across the sharp tip
    assert np.mean(np.abs(spacing / median - 1) < 0.05) > 0.95
    assert np.allclose(median[..., 0] * (table.n_points - 1), table.loop_length_m, rtol=0.05)
    # the upper branch leaves along the launch axis: the second point sits at phi above the horizontal
    ang = np.degrees(np.arctan2(c[:, :, 1, 1], c[:, :, 1, 0]))
    assert np.allclose(ang, table.phi_deg[None, :], atol=6.0)
    # and the loop comes back to the eyelet (the return point is within a centimetre of the exit)
    assert np.all(np.linalg.norm(c[:, :, -1], axis=2) < 0.01)


def test_committed_table_is_what_the_simulator_produces():
    """Regenerating one entry reproduces the committed contour (else regenerate the file)."""
    table = ShapeTable.load(DEFAULT_TABLE_PATH)
    s = table.rope_speed_mps.tolist().index(5.0)
    p = table.phi_deg.tolist().index(10.0)
    fresh = steady_contour_xz_m(ShooterParams(), phi_deg=10.0, rope_speed_mps=5.0, loop_length_m=table.loop_length_m,
                                n_points=table.n_points)
    assert np.abs(fresh - table.contours_m[s, p]).max() < 1e-5


def test_shape_export_cli_writes_a_loadable_table(tmp_path):
    from robowrangler_sim.string_shooter.shape_export import main

    out = tmp_path / "table.json"
    assert main(["--out", str(out), "--speeds", "5", "--loop-length", "0.6", "--points", "12", "--settle", "0.5"]) == 0
    table = ShapeTable.load(out)
    assert table.contours_m.shape == (1, 15, 12, 2)
    assert table.loop_length_m == 0.6


def test_shape_export_cli_refuses_bad_input(tmp_path, capsys):
    from robowrangler_sim.string_shooter.shape_export import main

    assert main(["--out", str(tmp_path / "t.json"), "--speeds", "5", "5"]) == 2
    assert "rope_speed_mps" in capsys.readouterr().err
