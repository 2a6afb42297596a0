"""Seeing the chain: headless PNG frames and MP4 (MuJoCo offscreen), and the interactive viewer.

Headless rendering needs an OpenGL backend chosen BEFORE mujoco is first imported: this module sets
MUJOCO_GL=osmesa (and PYOPENGL_PLATFORM=osmesa) when they are unset, which only helps if it is imported
first; otherwise export them in the shell. OSMesa comes from Debian's ``libosmesa6``
(``apt-get install -y libosmesa6``); EGL (``MUJOCO_GL=egl``, libegl1) works too where a GPU exists.
MP4 files are written with OpenCV's VideoWriter (fourcc ``mp4v``); no ffmpeg binary is needed.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")
if os.environ["MUJOCO_GL"] in ("osmesa", "egl"):
    os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])

from pathlib import Path  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from robowrangler_sim.chain.errors import ChainModelError  # noqa: E402


class ChainRenderer:
    """Offscreen renderer of a ChainPlant with a side camera that follows the loop.

    Args:
        plant: the ChainPlant to draw.
        width_px, height_px: image size (at most 1280 x 720, the model's offscreen buffer).
        azimuth_deg, elevation_deg: camera direction (azimuth 90: looking along +y, x to the right).
        distance_m: camera distance; None frames the loop (0.9 loop lengths).
    Use as a context manager, or call close(): the GL context is released explicitly.
    """

    def __init__(self, plant, *, width_px: int = 640, height_px: int = 360, azimuth_deg: float = 90.0,
                 elevation_deg: float = -12.0, distance_m: float | None = None) -> None:
        if not (16 <= width_px <= 1280 and 16 <= height_px <= 720):
            raise ChainModelError(f"width_px/height_px: expected 16..1280 x 16..720, got {width_px} x {height_px}")
        self.plant = plant
        self._renderer = mujoco.Renderer(plant.model, height=height_px, width=width_px)
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.camera.azimuth = azimuth_deg
        self.camera.elevation = elevation_deg
        self.camera.distance = distance_m if distance_m is not None else 0.9 * plant.loop_length_m()
        self._fixed_distance = distance_m is not None

    def frame(self) -> np.ndarray:
        """Render the current state. Returns shape (H, W, 3) uint8 RGB."""
        pts = self.plant.chain_points_m()
        centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        self.camera.lookat[:] = centre
        if not self._fixed_distance:
            self.camera.distance = max(0.6, 0.9 * self.plant.loop_length_m())
        self._renderer.update_scene(self.plant.data, camera=self.camera)
        return self._renderer.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __enter__(self) -> "ChainRenderer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_png(path: str | Path, frame_rgb: np.ndarray) -> Path:
    """Write an (H, W, 3) uint8 RGB frame as PNG."""
    import cv2

    path = Path(path)
    if not cv2.imwrite(str(path), cv2.cvtColor(np.ascontiguousarray(frame_rgb), cv2.COLOR_RGB2BGR)):
        raise OSError(f"could not write PNG {path}")
    return path


def write_mp4(path: str | Path, frames_rgb: list[np.ndarray], *, fps: float = 30.0) -> Path:
    """Write (H, W, 3) uint8 RGB frames as an MP4 (OpenCV, fourcc mp4v)."""
    import cv2

    if not frames_rgb:
        raise ChainModelError("frames_rgb: expected at least one frame, got none")
    h, w = frames_rgb[0].shape[:2]
    path = Path(path)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), float(fps), (w, h))
    if not writer.isOpened():
        raise OSError(f"OpenCV could not open an mp4v VideoWriter for {path}")
    try:
        for f in frames_rgb:
            writer.write(cv2.cvtColor(np.ascontiguousarray(f), cv2.COLOR_RGB2BGR))
    finally:
        writer.release()
    return path


def launch_viewer(plant, *, step_inputs=None) -> None:  # pragma: no cover - needs a display
    """MuJoCo's interactive viewer on the plant where a display exists (MUJOCO_GL=glfw).

    ``step_inputs(t_s) -> PlantInputs`` scripts the inputs; None keeps the last inputs.
    """
    import time

    import mujoco.viewer

    with mujoco.viewer.launch_passive(plant.model, plant.data) as viewer:
        while viewer.is_running():
            start = time.perf_counter()
            plant.step(step_inputs(plant.time_s) if step_inputs is not None else None)
            viewer.sync()
            time.sleep(max(0.0, plant.params.timestep_s - (time.perf_counter() - start)))
