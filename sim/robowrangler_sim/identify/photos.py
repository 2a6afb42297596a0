"""The photos of an identification and what is known about each: phi, rope speed, where the module is.

Two ways to say it:

- a manifest (JSON, schema ``robowrangler.identify_manifest/1``)::

    {"schema": "robowrangler.identify_manifest/1",
     "calibration": {"marker": {"dictionary": "DICT_4X4_50", "id": 0, "side_m": 0.2}},
                   # or {"intrinsics": {"focal_px": 2900, "distance_m": 3.0, "principal_px": [u, v],
                   #                    "yaw_deg": 0, "pitch_deg": 0, "roll_deg": 0}}
     "exit_px": [u, v],             # the guide exit in the image (every photo unless it gives its own)
     "return_px": [u, v],           # optional: where the rope re-enters the module (default: the exit)
     "loop_length_m": 2.0,          # optional: checked against what the photos measure
     "photos": [{"file": "a.png", "phi_deg": -30, "rope_speed_mps": 5.0, "exit_px": ..., "return_px": ...}]}

  File names are relative to the manifest's folder.
- file names: ``..._phi-30_v5.0.png`` (``phi`` then a signed number in degrees; ``v`` then the rope speed
  in m/s, optional when the speed is given for all photos), with the geometry given separately.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from robowrangler_sim.identify.errors import ManifestError, PhotoSetError, PhotoUnreadable

MANIFEST_SCHEMA = "robowrangler.identify_manifest/1"
_PHI_RE = re.compile(r"phi[_=]?([+-]?\d+(?:\.\d+)?)", re.IGNORECASE)
_SPEED_RE = re.compile(r"(?:^|[_\-.])v[_=]?(\d+(?:\.\d+)?)(?:mps)?(?=$|[_\-.])", re.IGNORECASE)


@dataclass(frozen=True)
class PhotoEntry:
    """One photo: its file, inclination (deg), rope speed (m/s), and where the exit / return point are (px)."""

    path: Path
    phi_deg: float
    rope_speed_mps: float
    exit_px: tuple[float, float] | None = None
    return_px: tuple[float, float] | None = None


@dataclass(frozen=True)
class PhotoSet:
    """Photos plus the set-wide facts: calibration spec (dict, see module doc), expected loop length."""

    photos: tuple[PhotoEntry, ...]
    calibration: dict = field(default_factory=dict)
    loop_length_m: float | None = None
    source: Path | None = None


def _point(value, where: Path, name: str) -> tuple[float, float] | None:
    if value is None:
        return None
    try:
        u, v = (float(c) for c in value)
    except (TypeError, ValueError):
        raise ManifestError(where, f"{name}: expected [u, v] in pixels, got {value!r}") from None
    if not (math.isfinite(u) and math.isfinite(v)):
        raise ManifestError(where, f"{name}: expected finite pixel coordinates, got {value!r}")
    return (u, v)


def _number(value, where: Path, name: str, *, positive: bool = False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ManifestError(where, f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(x) or (positive and x <= 0):
        raise ManifestError(where, f"{name}: expected a {'positive ' if positive else ''}finite number, got {value!r}")
    return x


def load_manifest(path: str | Path) -> PhotoSet:
    """Read a manifest (see module doc); raises ManifestError naming the manifest or the photo entry."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as exc:
        raise ManifestError(path, f"cannot read the manifest ({exc.strerror or exc})") from exc
    except json.JSONDecodeError as exc:
        raise ManifestError(path, f"not valid JSON ({exc})") from exc
    if not isinstance(data, dict) or data.get("schema") != MANIFEST_SCHEMA:
        got = data.get("schema") if isinstance(data, dict) else type(data).__name__
        raise ManifestError(path, f"schema: expected {MANIFEST_SCHEMA!r}, got {got!r}")
    entries = data.get("photos")
    if not isinstance(entries, list) or not entries:
        raise ManifestError(path, "photos: expected a non-empty list of {file, phi_deg, rope_speed_mps}")
    exit_px = _point(data.get("exit_px"), path, "exit_px")
    return_px = _point(data.get("return_px"), path, "return_px")
    photos = []
    for k, e in enumerate(entries):
        if not isinstance(e, dict) or "file" not in e:
            raise ManifestError(path, f"photos[{k}]: expected an object with 'file', got {e!r}")
        where = path.parent / str(e["file"])
        if e.get("phi_deg") is None:
            raise ManifestError(where, f"phi_deg: missing (manifest {path.name}, photos[{k}])")
        if e.get("rope_speed_mps") is None:
            raise ManifestError(where, f"rope_speed_mps: missing (manifest {path.name}, photos[{k}])")
        photos.append(PhotoEntry(path=where, phi_deg=_number(e["phi_deg"], where, "phi_deg"),
                                 rope_speed_mps=_number(e["rope_speed_mps"], where, "rope_speed_mps", positive=True),
                                 exit_px=_point(e.get("exit_px"), where, "exit_px") or exit_px,
                                 return_px=_point(e.get("return_px"), where, "return_px") or return_px))
    calibration = data.get("calibration") or {}
    if not isinstance(calibration, dict):
        raise ManifestError(path, f"calibration: expected an object, got {calibration!r}")
    loop_len = data.get("loop_length_m")
    return PhotoSet(photos=tuple(photos), calibration=calibration,
                    loop_length_m=None if loop_len is None else _number(loop_len, path, "loop_length_m", positive=True),
                    source=path)


def entry_from_name(path: str | Path, *, rope_speed_mps: float | None = None,
                    exit_px: tuple[float, float] | None = None,
                    return_px: tuple[float, float] | None = None) -> PhotoEntry:
    """A photo whose phi (and speed, unless given) is in its file name, e.g. ``loop_phi-30_v5.0.png``."""
    path = Path(path)
    m = _PHI_RE.search(path.stem)
    if m is None:
        raise ManifestError(path, "phi missing: expected 'phi<degrees>' in the file name (e.g. loop_phi-30_v5.0.png) "
                                  "or a manifest")
    speed = rope_speed_mps
    if speed is None:
        ms = _SPEED_RE.search(path.stem)
        if ms is None:
            raise ManifestError(path, "rope speed missing: expected 'v<m/s>' in the file name (e.g. loop_phi-30_v5.0.png),"
                                      " --rope-speed-mps, or a manifest")
        speed = float(ms.group(1))
    if not (math.isfinite(speed) and speed > 0):
        raise ManifestError(path, f"rope_speed_mps: expected > 0, got {speed!r}")
    return PhotoEntry(path=path, phi_deg=float(m.group(1)), rope_speed_mps=float(speed), exit_px=exit_px,
                      return_px=return_px)


def check_photo_set(photos) -> dict[float, list[PhotoEntry]]:
    """Group by speed, each sorted by phi; every speed must have the same angles (at least two), once each.

    Returns: {rope_speed_mps: [entries ascending in phi]}. Raises PhotoSetError naming the files.
    """
    photos = list(photos)
    if not photos:
        raise PhotoSetError(None, "no photos given")
    by_speed: dict[float, list[PhotoEntry]] = {}
    for p in photos:
        by_speed.setdefault(round(p.rope_speed_mps, 6), []).append(p)
    for speed, group in by_speed.items():
        seen: dict[float, PhotoEntry] = {}
        for p in group:
            key = round(p.phi_deg, 6)
            if key in seen:
                raise PhotoSetError(p.path, f"phi {p.phi_deg:g} deg at {speed:g} m/s repeated: also {seen[key].path}")
            seen[key] = p
        group.sort(key=lambda e: e.phi_deg)
    angle_sets = {s: [round(p.phi_deg, 6) for p in g] for s, g in by_speed.items()}
    all_angles = sorted({a for angles in angle_sets.values() for a in angles})
    for speed, angles in angle_sets.items():
        missing = [a for a in all_angles if a not in angles]
        if missing:
            raise PhotoSetError(by_speed[speed][0].path,
                                f"phi missing at {speed:g} m/s: {', '.join(f'{a:g}' for a in missing)} deg (the "
                                f"other speeds have them; a table needs the same angles at every speed)")
    if len(all_angles) < 2:
        raise PhotoSetError(photos[0].path, f"expected photos at two or more angles, got only phi {all_angles[0]:g} deg")
    return {s: by_speed[s] for s in sorted(by_speed)}


def read_gray(path: str | Path) -> np.ndarray:
    """The photo as an 8-bit gray image (H, W); PhotoUnreadable names the file."""
    path = Path(path)
    if not path.is_file():
        raise PhotoUnreadable(path, "no such file")
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None or img.size == 0:
        raise PhotoUnreadable(path, "not an image OpenCV can read (PNG, JPEG, TIFF, ...)")
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    if img.dtype != np.uint8:
        img = cv2.normalize(img, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    return img
