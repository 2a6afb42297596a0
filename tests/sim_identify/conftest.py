"""Fixtures of the identification tests: small synthetic photo sets with their ground truth.

A 1 m loop (the shipped default table's contours, scaled: a similar figure) photographed at about 1 mm
per pixel on 0.6 MP, so that a set renders and identifies in a few seconds; everything that makes the
bench's 4 MP photos realistic is there (camera off the normal, fuzz, motion blur, clutter, uneven light,
the module over the exit, an ArUco marker).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from robowrangler_sim.chain.default_table import load_default_shape_table
from robowrangler_sim.string_shooter.synthetic_photos import PhotoSetup, write_photo_set

LOOP_SCALE = 0.5  # the default table's 2 m loop -> 1 m

SMALL_SETUP = PhotoSetup(width_px=880, height_px=800, focal_px=1500.0, distance_m=1.5, aim_xz_m=(0.22, -0.15),
                         marker_side_m=0.15, marker_centre_xz_m=(0.10, -0.40), clutter=20, cables=1)


@dataclass(frozen=True)
class PhotoSetFixture:
    manifest: Path
    folder: Path
    truth: dict          # {(speed, phi): dense true centre line (K, 2), metres}
    loop_length_m: float


def make_set(folder: Path, shapes, *, seed: int, setup: PhotoSetup = SMALL_SETUP) -> PhotoSetFixture:
    default = load_default_shape_table()
    spec = [(phi, v, LOOP_SCALE * default.contour(phi, rope_speed_mps=v)) for phi, v in shapes]
    manifest, photos = write_photo_set(folder, spec, setup=setup, seed=seed)
    truth = {(p.rope_speed_mps, p.phi_deg): p.truth_xz_m for p in photos}
    lengths = [float(np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1))) for c in truth.values()]
    return PhotoSetFixture(manifest=manifest, folder=Path(folder), truth=truth, loop_length_m=float(np.median(lengths)))


@pytest.fixture(scope="session")
def photo_set(tmp_path_factory) -> PhotoSetFixture:
    """Five angles on a 10-deg grid at 5 m/s, plus the two angles between the first three (held out)."""
    folder = tmp_path_factory.mktemp("identify_set")
    return make_set(folder, [(phi, 5.0) for phi in (-30.0, -25.0, -20.0, -15.0, -10.0, 0.0, 10.0)], seed=3)


@pytest.fixture(scope="session")
def two_speed_set(tmp_path_factory) -> PhotoSetFixture:
    """Two angles at two rope speeds."""
    folder = tmp_path_factory.mktemp("identify_two_speeds")
    return make_set(folder, [(phi, v) for v in (4.0, 8.0) for phi in (-20.0, 20.0)], seed=5)


def rewrite_manifest(src: PhotoSetFixture, dst: Path, *, keep=None, **changes) -> Path:
    """A copy of a set's manifest in ``dst`` (photos by absolute path), some photos only, fields changed."""
    data = json.loads(src.manifest.read_text())
    photos = [dict(p, file=str(src.folder / p["file"])) for p in data["photos"]
              if keep is None or p["phi_deg"] in keep]
    data.update(changes, photos=photos)
    dst.mkdir(parents=True, exist_ok=True)
    path = dst / "manifest.json"
    path.write_text(json.dumps(data))
    return path


@pytest.fixture()
def manifest_copy():
    """rewrite_manifest, for the tests (conftest modules are not importable under --import-mode=importlib)."""
    return rewrite_manifest


@pytest.fixture(scope="session")
def small_setup() -> PhotoSetup:
    """The camera and scene of the test photo sets."""
    return SMALL_SETUP
