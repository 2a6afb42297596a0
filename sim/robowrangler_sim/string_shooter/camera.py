"""Synthetic camera images of the loop for the identification pipeline: a pinhole camera, a textured
background, a lit rope, optics blur, motion blur over the exposure, and sensor noise.

The rope is drawn as a tube of its real diameter, supersampled so that sub-pixel widths give partial
coverage; ``render_loop`` returns the 8-bit image together with the ground truth (coverage mask and
the projected contour) so that a pipeline can be scored against it.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .params import StringShooterParamError


@dataclass(frozen=True)
class PinholeCamera:
    """An ideal pinhole camera.

    Attributes:
        width_px, height_px: image size.
        focal_px: focal length in pixels (square pixels, principal point at the image centre).
        position_m: shape (3,), optical centre in the world.
        look_at_m: shape (3,), a point on the optical axis.
        up: shape (3,), world direction that appears upward in the image.
    """

    width_px: int = 640
    height_px: int = 480
    focal_px: float = 800.0
    position_m: tuple = (0.5, -3.0, 0.0)
    look_at_m: tuple = (0.5, 0.0, 0.0)
    up: tuple = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        if int(self.width_px) < 8 or int(self.height_px) < 8:
            raise StringShooterParamError(
                f"width_px, height_px: expected >= 8, got {self.width_px} x {self.height_px}"
            )
        if not (np.isfinite(self.focal_px) and self.focal_px > 0):
            raise StringShooterParamError(f"focal_px: expected > 0, got {self.focal_px!r}")
        fwd = np.asarray(self.look_at_m, float) - np.asarray(self.position_m, float)
        if np.linalg.norm(fwd) == 0:
            raise StringShooterParamError("look_at_m: expected a point different from position_m, got the same")
        if np.linalg.norm(np.cross(fwd, np.asarray(self.up, float))) < 1e-9:
            raise StringShooterParamError("up: expected a direction not parallel to the optical axis")

    def rotation(self) -> np.ndarray:
        """World-to-camera rotation (3, 3): rows are the camera x (right), y (down), z (forward) axes."""
        z = np.asarray(self.look_at_m, float) - np.asarray(self.position_m, float)
        z /= np.linalg.norm(z)
        x = np.cross(z, np.asarray(self.up, float))
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        return np.vstack([x, y, z])

    def project(self, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project world points (M, 3) to pixels (M, 2) (u right, v down) and depths (M,) in metres."""
        pts = np.asarray(points_m, float).reshape(-1, 3)
        cam = (pts - np.asarray(self.position_m, float)) @ self.rotation().T
        depth = cam[:, 2]
        safe = np.where(depth > 1e-6, depth, np.nan)
        u = self.focal_px * cam[:, 0] / safe + 0.5 * (self.width_px - 1)
        v = self.focal_px * cam[:, 1] / safe + 0.5 * (self.height_px - 1)
        return np.column_stack([u, v]), depth


def side_camera(*, guide_m, e1, distance_m: float = 2.5, loop_length_m: float = 2.0, **kw) -> PinholeCamera:
    """A camera looking at the loop plane from the side, centred half a loop-length ahead of the guide.

    Args: guide_m, e1 shape (3,): the eyelet position and launch axis (Frame.points_m[0], Frame.e1).
    """
    g = np.asarray(guide_m, float)
    heading = np.array([e1[0], e1[1], 0.0])
    heading = heading / np.linalg.norm(heading) if np.linalg.norm(heading) > 1e-9 else np.array([1.0, 0.0, 0.0])
    side = np.array([-heading[1], heading[0], 0.0])
    target = g + 0.25 * loop_length_m * heading - np.array([0.0, 0.0, 0.1 * loop_length_m])
    return PinholeCamera(position_m=tuple(target - distance_m * side), look_at_m=tuple(target), **kw)


@dataclass(frozen=True)
class ImageStyle:
    """How the picture looks. Gray levels are 0..255.

    Attributes:
        background_top, background_bottom: vertical gradient of the background.
        texture_amplitude: amplitude of a smooth random texture on the background.
        rope_ambient, rope_diffuse: rope brightness = ambient + diffuse x lit fraction (Lambert on a tube).
        light_dir: shape (3,), direction the light comes from.
        optics_blur_px: Gaussian blur sigma of the lens.
        noise_std: Gaussian read noise; shot_noise: scale of signal-dependent noise (std = sqrt(level) x it).
        supersample: rendering oversampling factor for sub-pixel rope widths.
    """

    background_top: float = 70.0
    background_bottom: float = 30.0
    texture_amplitude: float = 12.0
    rope_ambient: float = 150.0
    rope_diffuse: float = 90.0
    light_dir: tuple = (0.3, -0.5, 1.0)
    optics_blur_px: float = 0.7
    noise_std: float = 2.0
    shot_noise: float = 0.3
    supersample: int = 4


def _background(style: ImageStyle, h: int, w: int, rng: np.random.Generator) -> np.ndarray:
    grad = np.linspace(style.background_top, style.background_bottom, h)[:, None] * np.ones((1, w))
    coarse = rng.standard_normal((max(h // 32, 2), max(w // 32, 2)))
    texture = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)
    texture /= max(np.abs(texture).max(), 1e-9)
    return grad + style.texture_amplitude * texture


def _draw_rope(points_m: np.ndarray, camera: PinholeCamera, style: ImageStyle, diameter_m: float):
    """Coverage (H, W) in 0..1 and rope brightness (H, W) (gray level where covered) for one instant."""
    s = int(style.supersample)
    h, w = camera.height_px, camera.width_px
    cov = np.zeros((h * s, w * s), np.float32)
    lum = np.zeros((h * s, w * s), np.float32)
    area = np.zeros((h * s, w * s), np.float32)
    uv, depth = camera.project(points_m)
    light = np.asarray(style.light_dir, float)
    light /= np.linalg.norm(light)
    for i in range(len(points_m) - 1):
        if not (depth[i] > 0 and depth[i + 1] > 0):
            continue
        t = points_m[i + 1] - points_m[i]
        tl = np.linalg.norm(t)
        if tl <= 0:
            continue
        lit = np.sqrt(max(0.0, 1.0 - float(np.dot(t / tl, light)) ** 2))
        width_px = camera.focal_px * diameter_m / (0.5 * (depth[i] + depth[i + 1])) * s
        thick = max(1, int(round(width_px)))
        a = tuple(int(round(c * s * 16)) for c in uv[i] + 0.5 / s)
        b = tuple(int(round(c * s * 16)) for c in uv[i + 1] + 0.5 / s)
        cv2.line(cov, a, b, min(1.0, width_px / thick), thick, cv2.LINE_AA, 4)
        cv2.line(lum, a, b, style.rope_ambient + style.rope_diffuse * lit, thick, cv2.LINE_AA, 4)
        cv2.line(area, a, b, 1.0, thick, cv2.LINE_AA, 4)
    cov = cv2.resize(cov, (w, h), interpolation=cv2.INTER_AREA)
    lum = cv2.resize(lum, (w, h), interpolation=cv2.INTER_AREA)
    area = cv2.resize(area, (w, h), interpolation=cv2.INTER_AREA)
    level = np.where(area > 1e-6, lum / np.maximum(area, 1e-6), 0.0)
    return np.clip(cov, 0.0, 1.0).astype(float), level.astype(float)


@dataclass(frozen=True)
class RenderedImage:
    """An image with its ground truth.

    Attributes:
        image: shape (H, W), uint8 gray image.
        coverage: shape (H, W), fraction of each pixel covered by rope (exposure-averaged), 0..1.
        contour_px: shape (M, 2), the rope's projected points (u, v) at the middle of the exposure.
    """

    image: np.ndarray
    coverage: np.ndarray
    contour_px: np.ndarray


def render_loop(points_m, camera: PinholeCamera, *, seed: int, style: ImageStyle | None = None,
                rope_diameter_m: float = 2.0e-3) -> RenderedImage:
    """Render the rope.

    Args:
        points_m: shape (M, 3), one rope polyline, or a sequence of them (instants across the exposure;
            their renders are averaged, which is the motion blur).
        camera: the pinhole camera.
        seed: seeds the background texture and the noise (same seed, same image).
        rope_diameter_m: drawn diameter.
    """
    style = style or ImageStyle()
    arr = np.asarray(points_m, dtype=float) if not isinstance(points_m, (list, tuple)) else None
    instants = [np.asarray(p, float) for p in points_m] if arr is None or arr.ndim == 3 else [arr]
    for k, p in enumerate(instants):
        if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 2:
            raise StringShooterParamError(f"points_m[{k}]: expected shape (M >= 2, 3), got {p.shape}")
    if not (np.isfinite(rope_diameter_m) and rope_diameter_m > 0):
        raise StringShooterParamError(f"rope_diameter_m: expected > 0, got {rope_diameter_m!r}")
    rng = np.random.default_rng(seed)
    h, w = camera.height_px, camera.width_px
    bg = _background(style, h, w, rng)
    cov_acc = np.zeros((h, w))
    img_acc = np.zeros((h, w))
    for p in instants:
        cov, level = _draw_rope(p, camera, style, rope_diameter_m)
        img_acc += bg * (1 - cov) + level * cov
        cov_acc += cov
    img = img_acc / len(instants)
    cov = cov_acc / len(instants)
    if style.optics_blur_px > 0:
        img = cv2.GaussianBlur(img, (0, 0), style.optics_blur_px)
    img = img + rng.standard_normal(img.shape) * np.sqrt(style.noise_std ** 2 +
                                                          style.shot_noise ** 2 * np.maximum(img, 0.0))
    image = np.clip(np.round(img), 0, 255).astype(np.uint8)
    contour, _ = camera.project(instants[len(instants) // 2])
    return RenderedImage(image=image, coverage=cov, contour_px=contour)


@dataclass(frozen=True)
class CameraFrame:
    """One synthetic camera frame of a run.

    Attributes:
        frame_index: counter from 0; time_s: middle of the exposure (simulation clock).
        rendered: the image and its ground truth.
        loop_xz_m: shape (M, 2), the true contour in the shape-table frame at time_s.
        phi_rad, rope_speed_mps: the module inclination and the rope speed at time_s.
    """

    frame_index: int
    time_s: float
    rendered: RenderedImage
    loop_xz_m: np.ndarray
    phi_rad: float
    rope_speed_mps: float


def film(sim, camera: PinholeCamera, *, duration_s: float, fps_hz: float = 30.0, exposure_s: float = 0.004,
         sub_frames: int = 4, seed: int = 0, style: ImageStyle | None = None):
    """Advance ``sim`` (a StringShooter) for ``duration_s`` and yield a CameraFrame every 1 / fps_hz.

    Each image averages ``sub_frames`` instants spread over ``exposure_s`` (motion blur); frame k uses
    the noise seed (seed, k), so the same seed gives the same film.
    """
    if not (np.isfinite(fps_hz) and fps_hz > 0):
        raise StringShooterParamError(f"fps_hz: expected > 0, got {fps_hz!r}")
    period = 1.0 / fps_hz
    if not (0.0 <= exposure_s < period):
        raise StringShooterParamError(f"exposure_s: expected in [0, {period:.4f}) at {fps_hz} fps, got {exposure_s!r}")
    if int(sub_frames) < 1:
        raise StringShooterParamError(f"sub_frames: expected >= 1, got {sub_frames!r}")
    n_frames = int(round(duration_s * fps_hz))
    step = exposure_s / sub_frames
    for k in range(n_frames):
        sim.step_for(period - exposure_s)
        instants, middle = [], None
        for j in range(sub_frames):
            sim.step_for(step)
            frame = sim.frame()
            instants.append(frame.points_m)
            if j == sub_frames // 2:
                middle = frame
        rendered = render_loop(instants, camera, seed=int(np.random.SeedSequence([seed, k]).generate_state(1)[0]),
                               style=style, rope_diameter_m=sim.params.rope.diameter_m)
        yield CameraFrame(frame_index=k, time_s=middle.time_s, rendered=rendered,
                          loop_xz_m=middle.loop_plane_xz_m(), phi_rad=middle.phi_rad,
                          rope_speed_mps=middle.rope_speed_mps)
