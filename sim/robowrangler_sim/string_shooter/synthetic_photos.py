"""Realistic synthetic photos of the flying loop, with their ground truth, for shape identification.

The camera of camera.py (a pinhole) is set a few degrees off the loop plane's normal and rolled; the
picture has what real photos of a wool rope at 4 m/s have and an ideal render lacks:

- fuzz: short fibres sticking out of the rope on both sides;
- motion blur along the rope: the steady loop does not move, the rope runs along it, so its twist
  pattern and fibres smear along the centre line over the exposure (``sub_exposures`` instants averaged);
- uneven light (vignetting, a gradient, a bright spot), sensor noise (read and shot), lens blur;
- a cluttered background (blocks, discs, a wall texture, cables away from the loop);
- partial occlusion by the module (a dark box at the exit, with the robot's arm behind it);
- a calibration marker (an ArUco marker of known size with a white margin) in the loop plane.

World frame: the loop plane is y = 0, x horizontal away from the robot, z up, the guide exit at the
origin, so a contour (x, z) of the shape-table frame (robowrangler_sim.shape_table) sits at (x, 0, z).

    setup = PhotoSetup()
    photo = render_photo(contour_xz_m, phi_deg=-10, rope_speed_mps=5.0, setup=setup, seed=3)
    cv2.imwrite("p.png", photo.image)          # photo.truth_xz_m is the true centre line
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from scipy.interpolate import CubicSpline

from .camera import PinholeCamera
from .params import StringShooterParamError

ARUCO_DICTIONARY = "DICT_4X4_50"


@dataclass(frozen=True)
class PhotoSetup:
    """Camera, lighting and scene of a synthetic photo set.

    Attributes:
        width_px, height_px, focal_px: the camera (square pixels, principal point at the centre).
        distance_m: camera to the aim point, metres.
        yaw_deg, pitch_deg, roll_deg: the camera's viewing direction off the plane normal (about the
            vertical, about the horizontal) and its rotation about its own axis, degrees.
        aim_xz_m: the point of the loop plane at the image centre (table frame).
        marker_side_m, marker_centre_xz_m, marker_id: the ArUco calibration marker in the loop plane
            (its edges level, its top up), drawn with a white margin of a quarter side.
        rope_diameter_m: the rope's diameter.
        rope_level, fibre_level: gray level of the lit rope and of its fibres (before the light field).
        fibres_per_m, fibre_length_m: fuzz density and the range of fibre lengths.
        twist_period_m: period of the rope's brightness pattern (its twist).
        exposure_s, sub_exposures: shutter time and the instants averaged over it (motion blur).
        clutter: number of background objects; cables: thin cables drawn away from the loop.
        module: draw the module (and arm) over the exit.
        light_variation: strength of the uneven light (0 = even).
        noise_std, shot_noise: read noise and shot-noise scale (gray levels).
        optics_blur_px: lens blur sigma.
        supersample: oversampling of the rope render.
    """

    width_px: int = 2304
    height_px: int = 1728
    focal_px: float = 2900.0
    distance_m: float = 3.0
    yaw_deg: float = 4.0
    pitch_deg: float = -3.0
    roll_deg: float = 1.5
    aim_xz_m: tuple = (0.42, -0.2)
    marker_side_m: float = 0.20
    marker_centre_xz_m: tuple = (0.12, -0.78)
    marker_id: int = 0
    rope_diameter_m: float = 2.0e-3
    rope_level: float = 215.0
    fibre_level: float = 200.0
    fibres_per_m: float = 1500.0
    fibre_length_m: tuple = (1.0e-3, 6.0e-3)
    twist_period_m: float = 6.0e-3
    exposure_s: float = 1.0 / 250.0
    sub_exposures: int = 5
    clutter: int = 40
    cables: int = 2
    module: bool = True
    light_variation: float = 1.0
    noise_std: float = 2.5
    shot_noise: float = 0.5
    optics_blur_px: float = 0.8
    supersample: int = 3

    def __post_init__(self) -> None:
        if self.distance_m <= 0 or self.focal_px <= 0:
            raise StringShooterParamError(
                f"distance_m, focal_px: expected > 0, got {self.distance_m!r}, {self.focal_px!r}")
        if int(self.sub_exposures) < 1 or int(self.supersample) < 1:
            raise StringShooterParamError(
                f"sub_exposures, supersample: expected >= 1, got {self.sub_exposures}, {self.supersample}")

    def camera(self) -> PinholeCamera:
        """The pinhole camera of this setup."""
        aim = np.array([self.aim_xz_m[0], 0.0, self.aim_xz_m[1]])
        yaw, pitch, roll = (math.radians(a) for a in (self.yaw_deg, self.pitch_deg, self.roll_deg))
        view = np.array([math.sin(yaw) * math.cos(pitch), math.cos(yaw) * math.cos(pitch), math.sin(pitch)])
        up = np.array([0.0, 0.0, 1.0])
        up = up * math.cos(roll) + np.cross(view, up) * math.sin(roll) + view * np.dot(view, up) * (1 - math.cos(roll))
        return PinholeCamera(width_px=int(self.width_px), height_px=int(self.height_px), focal_px=float(self.focal_px),
                             position_m=tuple(aim - self.distance_m * view), look_at_m=tuple(aim), up=tuple(up))

    def plane_to_image(self) -> np.ndarray:
        """Homography (3, 3) from loop-plane (x, z) metres to image pixels (u, v)."""
        cam = self.camera()
        src = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        dst, _ = cam.project(_plane_to_world(src))
        return cv2.getPerspectiveTransform(src.astype(np.float32), dst.astype(np.float32))


@dataclass(frozen=True)
class SyntheticPhoto:
    """One synthetic photo and its ground truth.

    Attributes:
        image: shape (H, W), uint8 gray.
        truth_xz_m: shape (M, 2), the true centre line in the table frame (dense, exit first).
        exit_px, return_px: shape (2,), where the guide exit and the return point are in the image.
        phi_deg, rope_speed_mps: the photo's inclination and rope speed.
    """

    image: np.ndarray
    truth_xz_m: np.ndarray
    exit_px: np.ndarray
    return_px: np.ndarray
    phi_deg: float
    rope_speed_mps: float


def _plane_to_world(xz: np.ndarray) -> np.ndarray:
    xz = np.asarray(xz, float).reshape(-1, 2)
    return np.column_stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]])


def smooth_truth_curve(contour_xz_m: np.ndarray, *, spacing_m: float = 1.0e-3) -> np.ndarray:
    """A smooth dense curve through contour points: a cubic spline over chord length, sampled every spacing_m.

    Args:
        contour_xz_m: shape (M >= 4, 2), ordered contour points.
    Returns: shape (K, 2).
    """
    pts = np.asarray(contour_xz_m, float)
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 4:
        raise StringShooterParamError(f"contour_xz_m: expected shape (M >= 4, 2), got {pts.shape}")
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    spline = CubicSpline(s, pts, axis=0)
    n = max(int(s[-1] / spacing_m) + 1, 16)
    return spline(np.linspace(0.0, s[-1], n))


def _arc_length(curve: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])


def _light_field(setup: PhotoSetup, rng: np.random.Generator) -> np.ndarray:
    h, w = setup.height_px, setup.width_px
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    xn, yn = (xx - w / 2) / (w / 2), (yy - h / 2) / (h / 2)
    vignette = 1.0 - 0.30 * (xn ** 2 + yn ** 2) / 2
    angle = rng.uniform(0, 2 * np.pi)
    gradient = 1.0 + 0.25 * (np.cos(angle) * xn + np.sin(angle) * yn)
    cx, cy = rng.uniform(-0.8, 0.8, 2)
    spot = 1.0 + 0.35 * np.exp(-((xn - cx) ** 2 + (yn - cy) ** 2) / 0.15)
    field = vignette * gradient * spot
    return (1.0 + setup.light_variation * (field - 1.0)).astype(np.float32)


def _background(setup: PhotoSetup, keep_out_px: tuple, rng: np.random.Generator) -> np.ndarray:
    """Wall texture, blocks and discs anywhere, cables outside ``keep_out_px`` (u0, v0, u1, v1)."""
    h, w = setup.height_px, setup.width_px
    coarse = rng.standard_normal((max(h // 48, 2), max(w // 48, 2))).astype(np.float32)
    img = 85.0 + 18.0 * cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)
    fine = rng.standard_normal((h // 3 + 1, w // 3 + 1)).astype(np.float32)
    img += 4.0 * cv2.resize(fine, (w, h), interpolation=cv2.INTER_LINEAR)[:h, :w]
    for _ in range(int(setup.clutter)):
        level = float(rng.uniform(25, 190))
        cx, cy = rng.uniform(0, w), rng.uniform(0, h)
        size = rng.uniform(0.02, 0.15) * w
        if rng.uniform() < 0.6:
            box = ((cx, cy), (size, size * rng.uniform(0.3, 1.5)), rng.uniform(0, 180))
            pts = cv2.boxPoints(box).astype(np.int32)
            cv2.fillConvexPoly(img, pts, level, cv2.LINE_AA)
        else:
            cv2.circle(img, (int(cx), int(cy)), int(size / 2), level, -1, cv2.LINE_AA)
    u0, v0, u1, v1 = keep_out_px
    for _ in range(int(setup.cables)):
        for _attempt in range(50):
            a = rng.uniform([0, 0], [w, h])
            b = a + rng.uniform(0.1, 0.4) * w * np.array([math.cos(t := rng.uniform(0, np.pi)), math.sin(t)])
            lo, hi = np.minimum(a, b), np.maximum(a, b)
            if hi[0] < u0 or lo[0] > u1 or hi[1] < v0 or lo[1] > v1:
                cv2.line(img, tuple(int(c) for c in a), tuple(int(c) for c in b), float(rng.uniform(150, 230)),
                         int(rng.integers(2, 5)), cv2.LINE_AA)
                break
    return img


def _draw_marker(img: np.ndarray, setup: PhotoSetup) -> None:
    side = setup.marker_side_m
    cx, cz = setup.marker_centre_xz_m
    pattern_px = 240
    pattern = cv2.aruco.generateImageMarker(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, ARUCO_DICTIONARY)),
                                            int(setup.marker_id), pattern_px).astype(np.float32)
    margin = pattern_px // 4
    sheet = np.full((pattern_px + 2 * margin, pattern_px + 2 * margin), 235.0, np.float32)
    sheet[margin:margin + pattern_px, margin:margin + pattern_px] = np.where(pattern > 127, 235.0, 20.0)
    half = 0.5 * side * (pattern_px + 2 * margin) / pattern_px
    # sheet pixel (0, 0) is the top-left: plane (cx - half, cz + half)
    n = sheet.shape[0]
    # pixel-centre coordinates on both sides: the sheet's outer corners are at -0.5 and n - 0.5
    src = np.array([[0, 0], [n, 0], [n, n], [0, n]], np.float32) - 0.5
    plane = np.array([[cx - half, cz + half], [cx + half, cz + half], [cx + half, cz - half], [cx - half, cz - half]])
    dst, _ = setup.camera().project(_plane_to_world(plane))
    # render 4x supersampled in the marker's box, then average down (a printed sheet has no aliasing)
    ss = 4
    h, w = img.shape
    u0, v0 = np.maximum(np.floor(dst.min(axis=0)).astype(int) - 2, 0)
    u1, v1 = np.minimum(np.ceil(dst.max(axis=0)).astype(int) + 3, [w, h])
    dst_ss = (dst - np.array([u0, v0]) + 0.5) * ss - 0.5
    m = cv2.getPerspectiveTransform(src, dst_ss.astype(np.float32))
    size = ((u1 - u0) * ss, (v1 - v0) * ss)
    warped = cv2.warpPerspective(sheet, m, size, flags=cv2.INTER_LINEAR)
    cover = cv2.warpPerspective(np.ones_like(sheet), m, size, flags=cv2.INTER_NEAREST)
    warped = cv2.resize(warped * cover, (u1 - u0, v1 - v0), interpolation=cv2.INTER_AREA)
    cover = cv2.resize(cover, (u1 - u0, v1 - v0), interpolation=cv2.INTER_AREA)
    crop = img[v0:v1, u0:u1]
    crop *= 1.0 - cover
    crop += warped


def _draw_rope(img: np.ndarray, curve_xz: np.ndarray, rope_speed_mps: float, setup: PhotoSetup,
               rng: np.random.Generator) -> None:
    cam = setup.camera()
    s_ss = int(setup.supersample)
    uv, depth = cam.project(_plane_to_world(curve_xz))
    h, w = img.shape
    pad = 40
    u0, v0 = (np.floor(uv.min(axis=0)) - pad).astype(int)
    u1, v1 = (np.ceil(uv.max(axis=0)) + pad).astype(int)
    u0, v0, u1, v1 = max(u0, 0), max(v0, 0), min(u1, w), min(v1, h)
    cw, ch = u1 - u0, v1 - v0
    arc = _arc_length(curve_xz)
    length = float(arc[-1])
    tangent = np.gradient(curve_xz, axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    width_px = setup.focal_px * setup.rope_diameter_m / float(np.median(depth))
    thick = max(1, int(round(width_px * s_ss)))
    n_fibres = int(setup.fibres_per_m * length)
    f_s = rng.uniform(0, length, n_fibres)
    f_side = rng.choice([-1.0, 1.0], n_fibres)
    f_angle = rng.normal(0.0, 0.6, n_fibres)
    f_len = rng.uniform(*setup.fibre_length_m, n_fibres)
    f_alpha = rng.uniform(0.5, 1.0, n_fibres)
    twist_phase = rng.uniform(0, 2 * np.pi)
    chunk_m = 1.0e-3
    n_chunks = max(int(length / chunk_m), 2)
    chunk_s = np.linspace(0.0, length, n_chunks + 1)
    chunk_uv = np.column_stack([np.interp(chunk_s, arc, uv[:, 0]), np.interp(chunk_s, arc, uv[:, 1])])
    offset = np.array([u0, v0], float)

    def fix(p):
        return (p - offset + 0.5) * s_ss * 16 - 0.5 * 16

    k_sub = int(setup.sub_exposures)
    cov_acc = np.zeros((ch, cw), np.float32)
    lum_acc = np.zeros((ch, cw), np.float32)
    for k in range(k_sub):
        t = (k / max(k_sub - 1, 1) - 0.5) * setup.exposure_s
        shift = rope_speed_mps * t
        cov = np.zeros((ch * s_ss, cw * s_ss), np.float32)
        lum = np.zeros((ch * s_ss, cw * s_ss), np.float32)
        # fibres: attached to the moving rope, so they run along the centre line during the exposure
        fs = np.mod(f_s + shift, length)
        base = np.column_stack([np.interp(fs, arc, curve_xz[:, 0]), np.interp(fs, arc, curve_xz[:, 1])])
        tan = np.column_stack([np.interp(fs, arc, tangent[:, 0]), np.interp(fs, arc, tangent[:, 1])])
        nor = np.column_stack([np.interp(fs, arc, normal[:, 0]), np.interp(fs, arc, normal[:, 1])])
        direction = (nor * np.cos(f_angle)[:, None] + tan * np.sin(f_angle)[:, None]) * f_side[:, None]
        root = base + direction * (0.5 * setup.rope_diameter_m)
        tip = root + direction * f_len[:, None]
        root_uv, _ = cam.project(_plane_to_world(root))
        tip_uv, _ = cam.project(_plane_to_world(tip))
        a_fp = np.round(fix(root_uv)).astype(np.int64)
        b_fp = np.round(fix(tip_uv)).astype(np.int64)
        for i in range(n_fibres):
            a, b = (int(a_fp[i, 0]), int(a_fp[i, 1])), (int(b_fp[i, 0]), int(b_fp[i, 1]))
            cv2.line(cov, a, b, float(f_alpha[i]), 1, cv2.LINE_8, 4)
            cv2.line(lum, a, b, float(f_alpha[i] * setup.fibre_level), 1, cv2.LINE_8, 4)
        # body: brightness follows the twist pattern, which moves with the rope
        level = setup.rope_level * (1.0 + 0.12 * np.sin(2 * np.pi * (chunk_s - shift) / setup.twist_period_m
                                                         + twist_phase))
        p_fp = np.round(fix(chunk_uv)).astype(np.int64)
        for i in range(n_chunks):
            a, b = (int(p_fp[i, 0]), int(p_fp[i, 1])), (int(p_fp[i + 1, 0]), int(p_fp[i + 1, 1]))
            cv2.line(cov, a, b, 1.0, thick, cv2.LINE_8, 4)
            cv2.line(lum, a, b, float(level[i]), thick, cv2.LINE_8, 4)
        cov_acc += cv2.resize(cov, (cw, ch), interpolation=cv2.INTER_AREA)
        lum_acc += cv2.resize(lum, (cw, ch), interpolation=cv2.INTER_AREA)
    cov_acc /= k_sub
    lum_acc /= k_sub
    crop = img[v0:v1, u0:u1]
    crop *= 1.0 - cov_acc
    crop += lum_acc


def _draw_module(img: np.ndarray, phi_deg: float, setup: PhotoSetup) -> None:
    """The module (a dark box around the exit, launch axis at phi) and the robot's arm behind it."""
    cam = setup.camera()
    c, s = math.cos(math.radians(phi_deg)), math.sin(math.radians(phi_deg))
    axis, across = np.array([c, s]), np.array([-s, c])

    def poly(along_lo, along_hi, across_lo, across_hi):
        pts = [axis * a + across * b for a, b in ((along_lo, across_lo), (along_hi, across_lo),
                                                 (along_hi, across_hi), (along_lo, across_hi))]
        uv, _ = cam.project(_plane_to_world(np.array(pts)))
        return np.round(uv * 16).astype(np.int32)

    cv2.fillConvexPoly(img, poly(-0.60, -0.10, -0.03, 0.03), 60.0, cv2.LINE_AA, 4)   # arm
    cv2.fillConvexPoly(img, poly(-0.14, 0.02, -0.04, 0.035), 38.0, cv2.LINE_AA, 4)   # module body
    cv2.fillConvexPoly(img, poly(-0.13, 0.01, 0.015, 0.03), 70.0, cv2.LINE_AA, 4)    # a lit edge


def render_photo(contour_xz_m: np.ndarray, *, phi_deg: float, rope_speed_mps: float, setup: PhotoSetup | None = None,
                 seed: int = 0, return_xz_m: tuple | None = None) -> SyntheticPhoto:
    """Render one photo of a steady loop.

    Args:
        contour_xz_m: shape (M >= 4, 2), the loop's contour in the table frame (exit first); a smooth
            dense curve through it (smooth_truth_curve) is the ground truth.
        phi_deg: the module's inclination (draws the module); rope_speed_mps: sets the motion blur.
        seed: same seed, same photo.
        return_xz_m: where the rope re-enters the module (default: the contour's last point).
    """
    setup = setup or PhotoSetup()
    if not (math.isfinite(rope_speed_mps) and rope_speed_mps >= 0):
        raise StringShooterParamError(f"rope_speed_mps: expected >= 0, got {rope_speed_mps!r}")
    truth = smooth_truth_curve(contour_xz_m)
    rng = np.random.default_rng(seed)
    cam = setup.camera()
    uv, depth = cam.project(_plane_to_world(truth))
    if not np.all(depth > 0) or uv[:, 0].min() < 0 or uv[:, 1].min() < 0 or uv[:, 0].max() > setup.width_px - 1 \
            or uv[:, 1].max() > setup.height_px - 1:
        raise StringShooterParamError("contour_xz_m: the loop does not fit in the picture of this setup")
    keep_out = (uv[:, 0].min() - 60, uv[:, 1].min() - 60, uv[:, 0].max() + 60, uv[:, 1].max() + 60)
    img = _background(setup, keep_out, rng)
    _draw_marker(img, setup)
    _draw_rope(img, truth, rope_speed_mps, setup, rng)
    if setup.module:
        _draw_module(img, phi_deg, setup)
    img *= _light_field(setup, rng)
    if setup.optics_blur_px > 0:
        img = cv2.GaussianBlur(img, (0, 0), setup.optics_blur_px)
    img += rng.standard_normal(img.shape).astype(np.float32) * np.sqrt(
        setup.noise_std ** 2 + setup.shot_noise ** 2 * np.maximum(img, 0.0))
    image = np.clip(np.round(img), 0, 255).astype(np.uint8)
    ret = truth[-1] if return_xz_m is None else np.asarray(return_xz_m, float)
    ends, _ = cam.project(_plane_to_world(np.array([[0.0, 0.0], ret])))
    return SyntheticPhoto(image=image, truth_xz_m=truth, exit_px=ends[0], return_px=ends[1], phi_deg=float(phi_deg),
                          rope_speed_mps=float(rope_speed_mps))


def write_photo_set(out_dir, shapes, *, setup: PhotoSetup | None = None, seed: int = 0,
                    image_ext: str = "png") -> tuple[Path, list[SyntheticPhoto]]:
    """Render photos and write them with a manifest (manifest.json) the way a user would lay them out.

    Args:
        out_dir: a directory (created).
        shapes: iterable of (phi_deg, rope_speed_mps, contour_xz_m).
        seed: base seed; photo k uses (seed, k).
    Returns: (manifest path, the photos with their ground truth, in the order given).
    """
    setup = setup or PhotoSetup()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    photos, entries = [], []
    for k, (phi, speed, contour) in enumerate(shapes):
        sub_seed = int(np.random.SeedSequence([seed, k]).generate_state(1)[0])
        photo = render_photo(contour, phi_deg=phi, rope_speed_mps=speed, setup=setup, seed=sub_seed)
        name = f"loop_phi{phi:+05.1f}_v{speed:.1f}.{image_ext}"
        if not cv2.imwrite(str(out / name), photo.image):
            raise OSError(f"{out / name}: could not write the image")
        photos.append(photo)
        entries.append({"file": name, "phi_deg": float(phi), "rope_speed_mps": float(speed),
                        "return_px": [round(float(c), 2) for c in photo.return_px]})
    manifest = {
        "schema": "robowrangler.identify_manifest/1",
        "calibration": {"marker": {"dictionary": ARUCO_DICTIONARY, "id": int(setup.marker_id),
                                   "side_m": float(setup.marker_side_m)}},
        "exit_px": [round(float(c), 2) for c in photos[0].exit_px] if photos else None,
        "photos": entries,
    }
    path = out / "manifest.json"
    path.write_text(json.dumps(manifest, indent=1) + "\n")
    return path, photos
