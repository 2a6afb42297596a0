"""The stages on their own: manifest and file names, calibration, placement, deviation."""

from __future__ import annotations

import json

import numpy as np
import pytest

from robowrangler_sim.identify import ManifestError, PhotoSetError, entry_from_name, load_manifest
from robowrangler_sim.identify.calibration import PlaneCalibration
from robowrangler_sim.identify.deviation import deviation_m
from robowrangler_sim.identify.photos import PhotoEntry, check_photo_set
from robowrangler_sim.identify.resample import arc_length_m, common_placement, place_by_fractions, place_points, tip_index
from robowrangler_sim.identify.table_builder import build_table
from robowrangler_sim.string_shooter.synthetic_photos import PhotoSetup, smooth_truth_curve


def test_file_names_carry_phi_and_speed(tmp_path):
    e = entry_from_name(tmp_path / "loop_phi-30_v5.0.png")
    assert (e.phi_deg, e.rope_speed_mps) == (-30.0, 5.0)
    assert entry_from_name(tmp_path / "shot_phi+12.5_v8mps.jpg").phi_deg == 12.5
    assert entry_from_name(tmp_path / "phi=5.png", rope_speed_mps=4.0).rope_speed_mps == 4.0
    with pytest.raises(ManifestError, match="img_7.png: phi missing"):
        entry_from_name(tmp_path / "img_7.png", rope_speed_mps=4.0)
    with pytest.raises(ManifestError, match="loop_phi10.png: rope speed missing"):
        entry_from_name(tmp_path / "loop_phi10.png")


def test_manifest_errors_name_the_manifest(tmp_path):
    path = tmp_path / "m.json"
    path.write_text("{not json")
    with pytest.raises(ManifestError, match="m.json: not valid JSON"):
        load_manifest(path)
    path.write_text(json.dumps({"schema": "robowrangler.identify_manifest/1", "photos": [
        {"file": "a.png", "phi_deg": "steep", "rope_speed_mps": 5}]}))
    with pytest.raises(ManifestError, match="a.png: phi_deg: expected a number, got 'steep'"):
        load_manifest(path)
    with pytest.raises(ManifestError, match="cannot read the manifest"):
        load_manifest(tmp_path / "absent.json")


def test_photo_set_needs_two_angles_once_each(tmp_path):
    one = [PhotoEntry(path=tmp_path / "a.png", phi_deg=0.0, rope_speed_mps=5.0)]
    with pytest.raises(PhotoSetError, match="two or more angles"):
        check_photo_set(one)
    groups = check_photo_set([PhotoEntry(path=tmp_path / f"{p}.png", phi_deg=p, rope_speed_mps=v)
                              for v in (8.0, 5.0) for p in (10.0, -10.0)])
    assert list(groups) == [5.0, 8.0] and [e.phi_deg for e in groups[5.0]] == [-10.0, 10.0]


def test_intrinsics_calibration_is_the_camera_it_describes():
    setup = PhotoSetup(yaw_deg=5.0, pitch_deg=-4.0, roll_deg=2.0, aim_xz_m=(0.0, 0.0))
    cal = PlaneCalibration.from_intrinsics(focal_px=setup.focal_px, distance_m=setup.distance_m,
                                           principal_px=(0.5 * (setup.width_px - 1), 0.5 * (setup.height_px - 1)),
                                           yaw_deg=5.0, pitch_deg=-4.0, roll_deg=2.0)
    plane = np.array([[0.0, 0.0], [0.8, 0.3], [-0.4, -0.6], [1.0, -0.5]])
    pixels = cv2_project(setup, plane)
    np.testing.assert_allclose(cal.to_plane(pixels), plane, atol=1e-9)
    assert cal.metres_per_px((1000.0, 800.0)) == pytest.approx(setup.distance_m / setup.focal_px, rel=0.02)


def cv2_project(setup, plane_xz):
    uv, _ = setup.camera().project(np.column_stack([plane_xz[:, 0], np.zeros(len(plane_xz)), plane_xz[:, 1]]))
    return uv


def test_marker_calibration_measures_the_plane(photo_set, small_setup):
    import cv2

    ps = load_manifest(photo_set.manifest)
    img = cv2.imread(str(ps.photos[0].path), cv2.IMREAD_GRAYSCALE)
    cal = PlaneCalibration.from_marker(img, side_m=small_setup.marker_side_m)
    # plane points over the loop's area, 0.1 .. 0.5 m from the marker, seen by the true camera
    plane = np.array([[x, z] for x in np.linspace(-0.05, 0.5, 6) for z in np.linspace(-0.35, 0.2, 6)])
    measured = cal.to_plane(cv2_project(small_setup, plane)) + np.asarray(small_setup.marker_centre_xz_m)
    err = np.linalg.norm(measured - plane, axis=1)
    assert err.max() < 0.004  # metres, on a 1 m loop seen at 1 mm per pixel with a 15 cm marker


def test_curvature_placement_anchors_the_tip_and_keeps_the_ends():
    t = np.linspace(0, 2 * np.pi, 2001)
    curve = smooth_truth_curve(np.column_stack([0.5 * (1 - np.cos(t)), 0.08 * np.sin(t)])[::20])
    pts = place_points(curve, 21, placement="curvature")
    assert pts[0] == pytest.approx(curve[0]) and pts[-1] == pytest.approx(curve[-1])
    placement = common_placement([curve], 21)
    assert pts[placement.tip_index] == pytest.approx(curve[tip_index(curve)])
    chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert chords[placement.tip_index] < 0.6 * chords[2]     # denser round the tip than along the branch
    equal = place_points(curve, 21, placement="equal")
    # the gain at the same N
    assert deviation_m(curve, pts)[0] < 0.5 * deviation_m(curve, equal)[0]


def test_one_placement_for_the_whole_table():
    t = np.linspace(0, 2 * np.pi, 1001)
    contours = {5.0: {}}
    for phi, b in ((-10.0, 0.06), (0.0, 0.08), (10.0, 0.1)):
        c = smooth_truth_curve(np.column_stack([0.5 * (1 - np.cos(t)), b * np.sin(t)])[::10])
        contours[5.0][phi] = c
    table = build_table(contours, n_points=25, placement="curvature", loop_length_m=1.0, source="test")
    placement = common_placement(list(contours[5.0].values()), 25)
    for k, c in enumerate(contours[5.0].values()):
        np.testing.assert_allclose(table.contours_m[0, k], place_by_fractions(c, placement))
        assert np.argmax(np.linalg.norm(table.contours_m[0, k], axis=1)) == placement.tip_index
    assert arc_length_m(table.contours_m[0, 1])[-1] == pytest.approx(arc_length_m(contours[5.0][0.0])[-1], rel=0.01)
