"""Per-camera-frame observations of the simulated loop, shaped like the recording schema's records.

These build plain dicts for the ``/loop/observation`` and ``/sim/plant_truth`` channels of the
recording schema (protocol/recording/schemas/*.schema.json). recording.py writes them into MCAP files
together with the SIL firmware's telemetry; nothing here writes files.
"""

from __future__ import annotations

import math

import numpy as np

from ..shape_table import resample_by_arc_length
from .model import Frame
from .params import StringShooterParamError

AIRBORNE_DEPTH_FRACTION = 0.75


def is_airborne(frame: Frame, *, loop_length_m: float) -> bool:
    """True when the loop's lowest point is less than 0.75 x half its length below the exit (a hanging
    loop reaches about 0.95)."""
    depth = -float(np.min(frame.loop_plane_xz_m()[:, 1]))
    return depth < AIRBORNE_DEPTH_FRACTION * 0.5 * loop_length_m


def loop_observation_record(frame: Frame, *, camera_id: str, frame_index: int, n_points: int = 40) -> dict:
    """A ``/loop/observation`` record: the contour as n_points equally spaced [x_m, z_m] in the loop frame."""
    if not camera_id:
        raise StringShooterParamError("camera_id: expected a non-empty string, got ''")
    if isinstance(frame_index, bool) or not isinstance(frame_index, int) or frame_index < 0:
        raise StringShooterParamError(f"frame_index: expected an integer >= 0, got {frame_index!r}")
    if n_points < 2:
        raise StringShooterParamError(f"n_points: expected >= 2, got {n_points}")
    pts = resample_by_arc_length(frame.loop_plane_xz_m(), n_points)
    phi = math.atan2(math.sin(frame.phi_rad), math.cos(frame.phi_rad))
    return {
        "time_s": float(frame.time_s),
        "camera_id": camera_id,
        "frame_index": frame_index,
        "phi_rad": phi,
        "rope_speed_mps": float(frame.rope_speed_mps),
        "points_m": [[float(x), float(z)] for x, z in pts],
    }


def plant_truth_record(frame: Frame, *, loop_length_m: float) -> dict:
    """A ``/sim/plant_truth`` record: true rope speed and whether the loop flies."""
    return {
        "time_s": float(frame.time_s),
        "rope_speed_mps": float(frame.rope_speed_mps),
        "loop_airborne": is_airborne(frame, loop_length_m=loop_length_m),
    }
