"""Realistic synthetic photos for shape identification: the rope where the truth says, the module over the
exit, the marker where the setup says, determinism, bad input."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from robowrangler_sim.string_shooter import StringShooterParamError
from robowrangler_sim.string_shooter.synthetic_photos import (PhotoSetup, _plane_to_world, render_photo,
                                                              smooth_truth_curve, write_photo_set)

SETUP = PhotoSetup(width_px=640, height_px=560, focal_px=1100.0, distance_m=1.5, aim_xz_m=(0.3, -0.1),
                   marker_side_m=0.15, marker_centre_xz_m=(0.1, -0.33), clutter=10, cables=1)


def _loop(phi_deg: float = 0.0) -> np.ndarray:
    t = np.linspace(0.0, 2 * np.pi, 60)
    u, w = 0.3 * (1 - np.cos(t)), 0.08 * np.sin(t) - 0.01 * t / (2 * np.pi)
    c, s = np.cos(np.radians(phi_deg)), np.sin(np.radians(phi_deg))
    return np.column_stack([c * u - s * w, s * u + c * w])


def test_same_seed_same_photo_and_another_seed_another():
    a = render_photo(_loop(), phi_deg=0.0, rope_speed_mps=5.0, setup=SETUP, seed=4)
    b = render_photo(_loop(), phi_deg=0.0, rope_speed_mps=5.0, setup=SETUP, seed=4)
    c = render_photo(_loop(), phi_deg=0.0, rope_speed_mps=5.0, setup=SETUP, seed=5)
    assert np.array_equal(a.image, b.image) and not np.array_equal(a.image, c.image)
    np.testing.assert_array_equal(a.truth_xz_m, c.truth_xz_m)


def test_rope_is_bright_along_the_truth_and_the_module_hides_the_exit():
    photo = render_photo(_loop(), phi_deg=0.0, rope_speed_mps=5.0, setup=SETUP, seed=1)
    img = photo.image.astype(float)
    tophat = img - cv2.morphologyEx(img.astype(np.uint8), cv2.MORPH_OPEN, np.ones((9, 9), np.uint8))
    uv, _ = SETUP.camera().project(_plane_to_world(photo.truth_xz_m))
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(photo.truth_xz_m, axis=0), axis=1))])
    visible = (s > 0.05) & (s < s[-1] - 0.05)
    on_rope = tophat[np.round(uv[visible, 1]).astype(int), np.round(uv[visible, 0]).astype(int)]
    off_rope = tophat[np.round(uv[visible, 1] + 12).astype(int), np.round(uv[visible, 0]).astype(int)]
    assert np.median(on_rope) > np.median(off_rope) + 30
    u, v = np.round(photo.exit_px).astype(int)
    assert img[v, u] < 90  # the module (dark) covers the exit
    np.testing.assert_allclose(photo.exit_px, SETUP.camera().project(np.zeros((1, 3)))[0][0])


def test_marker_is_found_where_the_setup_puts_it():
    photo = render_photo(_loop(), phi_deg=10.0, rope_speed_mps=5.0, setup=SETUP, seed=2)
    det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50),
                                  cv2.aruco.DetectorParameters())
    corners, ids, _ = det.detectMarkers(photo.image)
    assert ids is not None and ids.ravel().tolist() == [0]
    cx, cz = SETUP.marker_centre_xz_m
    h = SETUP.marker_side_m / 2
    true_tl, _ = SETUP.camera().project(_plane_to_world(np.array([[cx - h, cz + h]])))
    assert np.linalg.norm(corners[0].reshape(4, 2)[0] - true_tl[0]) < 1.5


def test_set_writes_images_and_a_manifest(tmp_path):
    manifest, photos = write_photo_set(tmp_path, [(-10.0, 5.0, _loop(-10)), (10.0, 5.0, _loop(10))], setup=SETUP,
                                       seed=0)
    data = json.loads(manifest.read_text())
    assert [p["phi_deg"] for p in data["photos"]] == [-10.0, 10.0]
    assert data["calibration"]["marker"]["side_m"] == 0.15
    for p in data["photos"]:
        assert cv2.imread(str(tmp_path / p["file"]), cv2.IMREAD_GRAYSCALE).shape == (560, 640)


def test_bad_input():
    with pytest.raises(StringShooterParamError, match="does not fit in the picture"):
        render_photo(_loop() * 5.0, phi_deg=0.0, rope_speed_mps=5.0, setup=SETUP, seed=0)
    with pytest.raises(StringShooterParamError, match="rope_speed_mps"):
        render_photo(_loop(), phi_deg=0.0, rope_speed_mps=float("nan"), setup=SETUP, seed=0)
    with pytest.raises(StringShooterParamError, match="contour_xz_m"):
        smooth_truth_curve(np.zeros((3, 2)))
    with pytest.raises(StringShooterParamError, match="distance_m"):
        PhotoSetup(distance_m=0.0)
