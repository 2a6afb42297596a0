"""A loop candidate: the engine's Candidate (diagnose/candidates/base.py) on the loop's theta columns
(diagnose/loop/shape_model.py TH_*), compared on the contour channel."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability

ROTATING_RAD_S = np.deg2rad(5.0)


class LoopCandidate(Candidate):
    plant = "loop"
    channels = ("contour_normal_m",)


def rotation_frames(replay) -> int:
    """Frames where the module turns faster than 5 deg/s."""
    return int(np.sum(np.abs(replay.phidot_rad_s) > ROTATING_RAD_S))


__all__ = ["Identifiability", "LoopCandidate", "rotation_frames"]
