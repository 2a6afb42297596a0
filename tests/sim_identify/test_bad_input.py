"""Bad input: every error names the file at fault, and no table is written (not even a partial one)."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from robowrangler_sim.identify import (CalibrationError, ManifestError, NoLoopFound, PhotoSetError, PhotoUnreadable,
                                       SeveralLoops, identify_manifest, load_manifest)
from robowrangler_sim.identify.calibration import PlaneCalibration
from robowrangler_sim.identify.extract import extract_photo
from robowrangler_sim.identify.photos import PhotoEntry


def test_unreadable_photo_is_named(photo_set, tmp_path, manifest_copy):
    bad = tmp_path / "loop_phi-20.0_v5.0.png"
    bad.write_bytes(b"not a png at all")
    manifest = manifest_copy(photo_set, tmp_path, keep=(-30.0, -20.0))
    data = json.loads(manifest.read_text())
    data["photos"][1]["file"] = str(bad)
    manifest.write_text(json.dumps(data))
    with pytest.raises(PhotoUnreadable) as err:
        identify_manifest(manifest, workers=1)
    assert err.value.path == bad and str(bad) in str(err.value)


def test_missing_file_is_named(photo_set, tmp_path, manifest_copy):
    manifest = manifest_copy(photo_set, tmp_path, keep=(-30.0, -20.0))
    data = json.loads(manifest.read_text())
    data["photos"][0]["file"] = str(tmp_path / "nowhere.png")
    manifest.write_text(json.dumps(data))
    with pytest.raises(PhotoUnreadable, match="nowhere.png: no such file"):
        identify_manifest(manifest, workers=1)


def test_repeated_and_missing_phi(photo_set, tmp_path, manifest_copy):
    manifest = manifest_copy(photo_set, tmp_path / "a", keep=(-30.0, -20.0))
    data = json.loads(manifest.read_text())
    data["photos"][1]["phi_deg"] = -30.0
    manifest.write_text(json.dumps(data))
    with pytest.raises(PhotoSetError, match=r"phi -30 deg at 5 m/s repeated: also .*loop_phi-30.0_v5.0.png"):
        identify_manifest(manifest, workers=1)
    # a second speed lacking one of the first speed's angles
    data["photos"][1].update(phi_deg=-20.0)
    data["photos"].append(dict(data["photos"][0], rope_speed_mps=8.0))
    manifest.write_text(json.dumps(data))
    with pytest.raises(PhotoSetError, match="phi missing at 8 m/s: -20 deg"):
        identify_manifest(manifest, workers=1)
    del data["photos"][0]["phi_deg"]
    manifest.write_text(json.dumps(data))
    with pytest.raises(ManifestError, match=r"loop_phi-30.0_v5.0.png: phi_deg: missing"):
        identify_manifest(manifest, workers=1)


def test_no_loop_at_the_exit(photo_set):
    entry = load_manifest(photo_set.manifest).photos[0]
    away = PhotoEntry(path=entry.path, phi_deg=entry.phi_deg, rope_speed_mps=entry.rope_speed_mps,
                      exit_px=(30.0, 30.0), return_px=None)
    with pytest.raises(NoLoopFound, match="no rope loop touches the exit point") as err:
        extract_photo(away, load_manifest(photo_set.manifest).calibration)
    assert err.value.path == entry.path


@pytest.mark.parametrize("shift_px", [0, 40])
def test_several_loops_at_the_exit(photo_set, tmp_path, shift_px):
    ps = load_manifest(photo_set.manifest)
    entry = ps.photos[-1]  # phi = 10
    img = cv2.imread(str(entry.path), cv2.IMREAD_GRAYSCALE)
    # a second, smaller loop inside the first: the rope (top-hat) scaled by 0.5 about the exit, added on
    # top, leaving either the same exit or its own 40 px (4 cm) further along
    u, v = entry.exit_px
    rope = cv2.subtract(img, cv2.morphologyEx(img, cv2.MORPH_OPEN, np.ones((9, 9), np.uint8)))
    flip = cv2.warpAffine(rope, np.float32([[0.5, 0, 0.5 * u + shift_px], [0, 0.5, 0.5 * v]]),
                          (img.shape[1], img.shape[0]))
    two = tmp_path / "loop_phi+10.0_v5.0.png"
    cv2.imwrite(str(two), cv2.add(img, flip))
    calibration = PlaneCalibration.from_marker(img, side_m=ps.calibration["marker"]["side_m"])  # the copy hides it
    with pytest.raises(SeveralLoops, match="rope forks|loops share the exit|candidate loops touch") as err:
        extract_photo(PhotoEntry(path=two, phi_deg=10.0, rope_speed_mps=5.0, exit_px=entry.exit_px), ps.calibration,
                      calibration=calibration)
    assert err.value.path == two


def test_calibration_that_does_not_fit(photo_set, tmp_path, manifest_copy):
    # the manifest says the loop is 1.5 m; the marker says it is 1 m
    manifest = manifest_copy(photo_set, tmp_path / "a", keep=(-30.0, -20.0), loop_length_m=1.5)
    with pytest.raises(CalibrationError, match=r"calibration does not fit: the loop measures 0\.9\d\d m"):
        identify_manifest(manifest, workers=1)
    # one photo of another camera set-up: its marker is printed at a different size (same id, same side_m
    # written): that photo's loop measures 20 % long
    ps = load_manifest(photo_set.manifest)
    img = cv2.imread(str(ps.photos[1].path), cv2.IMREAD_GRAYSCALE)
    big = cv2.resize(img, None, fx=1.2, fy=1.2, interpolation=cv2.INTER_LINEAR)
    odd = tmp_path / "b" / "loop_phi-25.0_v5.0.png"
    odd.parent.mkdir()
    cv2.imwrite(str(odd), big[:img.shape[0], :img.shape[1]])
    manifest = manifest_copy(photo_set, tmp_path / "b", keep=(-30.0, -20.0, -10.0))
    data = json.loads(manifest.read_text())
    u, v = ps.photos[1].exit_px
    data["photos"].append({"file": str(odd), "phi_deg": -25.0, "rope_speed_mps": 5.0, "exit_px": [1.2 * u + 0.1, 1.2 * v + 0.1]})
    manifest.write_text(json.dumps(data))
    with pytest.raises(CalibrationError) as err:
        identify_manifest(manifest, workers=1)
    assert err.value.path == odd


def test_marker_not_in_photo(photo_set, tmp_path, manifest_copy):
    manifest = manifest_copy(photo_set, tmp_path, keep=(-30.0, -20.0),
                                calibration={"marker": {"side_m": 0.15, "id": 7}})
    with pytest.raises(CalibrationError, match=r"marker DICT_4X4_50 id 7 not found in the photo \(found ids \[0\]\)"):
        identify_manifest(manifest, workers=1)
