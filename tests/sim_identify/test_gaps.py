"""A rope that vanishes over a light object for a few centimetres: bridged, or (bridging off) a clear error."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from robowrangler_sim.identify import ExtractOptions, NoLoopFound, load_manifest
from robowrangler_sim.identify.deviation import deviation_m
from robowrangler_sim.identify.extract import extract_photo
from robowrangler_sim.identify.photos import PhotoEntry


@pytest.fixture()
def hidden_stretch(photo_set, tmp_path, small_setup):
    """The phi = -10 photo with 6 cm of the upper branch painted over in the background's level (the rope
    vanishes there as a light rope does over a light object)."""
    ps = load_manifest(photo_set.manifest)
    entry = next(p for p in ps.photos if p.phi_deg == -10.0)
    img = cv2.imread(str(entry.path), cv2.IMREAD_GRAYSCALE)
    truth = photo_set.truth[(5.0, -10.0)]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(truth, axis=0), axis=1))])
    stretch = truth[(s > 0.30) & (s < 0.36)]
    uv, _ = small_setup.camera().project(np.column_stack([stretch[:, 0], np.zeros(len(stretch)), stretch[:, 1]]))
    patch = np.zeros_like(img)
    cv2.polylines(patch, [np.round(uv).astype(np.int32)], False, 255, 25)
    ring = cv2.dilate(patch, np.ones((15, 15), np.uint8)) > patch
    img[patch > 0] = int(np.median(img[ring]))
    path = tmp_path / "loop_phi-10.0_v5.0.png"
    cv2.imwrite(str(path), img)
    entry = PhotoEntry(path=path, phi_deg=-10.0, rope_speed_mps=5.0, exit_px=entry.exit_px, return_px=entry.return_px)
    return entry, ps.calibration, truth


def test_a_gap_is_bridged(hidden_stretch, photo_set):
    entry, calibration, truth = hidden_stretch
    result = extract_photo(entry, calibration)
    assert result.gaps_bridged >= 1
    assert deviation_m(truth, result.contour_m)[0] < 0.006 * photo_set.loop_length_m


def test_without_bridging_the_broken_loop_is_named(hidden_stretch):
    entry, calibration, _ = hidden_stretch
    with pytest.raises(NoLoopFound, match="do not come back to the exit") as err:
        extract_photo(entry, calibration, options=ExtractOptions(max_gap_m=0.0))
    assert err.value.path == entry.path
