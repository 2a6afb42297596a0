"""Identification end to end on synthetic photos with known truth: accuracy, held-out angles, the gain
of curvature-aware placement, several speeds, and the table in the chain model."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.identify import identify, identify_manifest, load_manifest, write_identification
from robowrangler_sim.identify.deviation import deviation_m
from robowrangler_sim.identify.photos import PhotoSet
from robowrangler_sim.shape_table import ShapeTable

TARGET_FRACTION = 0.01  # max deviation <= 1 % of the loop length (the paper: 2 %)


def _subset(photo_set, phis):
    ps = load_manifest(photo_set.manifest)
    return PhotoSet(photos=tuple(p for p in ps.photos if p.phi_deg in phis), calibration=ps.calibration)


@pytest.fixture(scope="module")
def grid_result(photo_set):
    """The table from the 10-deg grid only (-30, -20, -10, 0, 10)."""
    return identify(_subset(photo_set, (-30.0, -20.0, -10.0, 0.0, 10.0)), workers=2)


def test_every_photo_yields_the_loop_within_a_few_millimetres(grid_result, photo_set):
    for r in grid_result.photos:
        truth = photo_set.truth[(5.0, r.entry.phi_deg)]
        worst, mean = deviation_m(truth, r.contour_m)
        assert worst < 0.006 * photo_set.loop_length_m, r.entry.path
        assert mean < 0.0025 * photo_set.loop_length_m
        assert r.loop_length_m == pytest.approx(photo_set.loop_length_m, rel=0.02)
        # exit first, out along the upper branch: the first points lie above the last ones
        assert r.contour_m[0] == pytest.approx([0.0, 0.0])
        assert r.contour_m[len(r.contour_m) // 10, 1] > r.contour_m[-len(r.contour_m) // 10, 1]


def test_table_meets_one_percent_on_photographed_and_held_out_angles(grid_result, photo_set):
    table = grid_result.table
    assert table.phi_deg.tolist() == [-30.0, -20.0, -10.0, 0.0, 10.0]
    for phi in (-30.0, -25.0, -20.0, -15.0, -10.0, 0.0, 10.0):   # -25 and -15 were not in the table
        worst, _ = deviation_m(photo_set.truth[(5.0, phi)], table.contour(phi))
        assert worst <= TARGET_FRACTION * photo_set.loop_length_m, phi


def test_curvature_aware_placement_beats_equal_chords_on_the_same_photos(grid_result, photo_set):
    from robowrangler_sim.identify.table_builder import build_table

    contours = {5.0: {r.entry.phi_deg: r.contour_m for r in grid_result.photos}}
    worst = {}
    for placement in ("equal", "curvature"):
        table = build_table(contours, n_points=21, placement=placement, loop_length_m=1.0, source="test")
        worst[placement] = max(deviation_m(photo_set.truth[(5.0, phi)], table.contour(phi))[0]
                               for phi in (-30.0, -25.0, -20.0, -15.0, -10.0, 0.0, 10.0))
    assert worst["curvature"] < 0.7 * worst["equal"]


def test_several_speeds_make_one_table(two_speed_set, tmp_path):
    result = identify_manifest(two_speed_set.manifest, workers=1)
    assert result.table.rope_speed_mps.tolist() == [4.0, 8.0]
    assert result.table.phi_deg.tolist() == [-20.0, 20.0]
    for (speed, phi), truth in two_speed_set.truth.items():
        worst, _ = deviation_m(truth, result.table.contour(phi, rope_speed_mps=speed))
        assert worst <= TARGET_FRACTION * two_speed_set.loop_length_m


def test_written_table_loads_unchanged_into_the_chain_model(grid_result, photo_set, tmp_path):
    from robowrangler_sim.chain.accuracy import steady_state_accuracy
    from robowrangler_sim.chain.params import ChainParams

    path = write_identification(grid_result, tmp_path / "table.json", figures_dir=tmp_path / "fig")
    loaded = ShapeTable.load(path)
    np.testing.assert_allclose(loaded.contours_m, grid_result.table.contours_m, atol=1e-6)
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == sorted(
        f"{r.entry.path.stem}_identified.png" for r in grid_result.photos)
    # the chain settles on the identified shape: the accuracy module reports it against the table
    report = steady_state_accuracy(loaded, params=ChainParams(n_links=20), settle_s=2.5, phi_deg=np.array([-10.0]))
    assert report.max_m[0] < 0.05 * report.loop_length_m
    assert report.mean_m[0] < 0.02 * report.loop_length_m
