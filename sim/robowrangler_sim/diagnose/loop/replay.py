"""Replay: the chain's loop (fast form, batched) driven by the recording's rope speed, guide position and phi;
predictions are the model contour's offsets along fixed normals (the nominal model's outward normals at each
frame and point), so that measured - predicted is the signed normal distance of the observed contour."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop.data import LoopData
from robowrangler_sim.diagnose.loop.shape_model import LoopShapeModel, phidot

CHANNEL = "contour_normal_m"


def outward_normals(points_m: np.ndarray) -> np.ndarray:
    """Unit normals (F, K, 2) left of the flow direction (exit -> tip -> return): outward of the loop."""
    tang = np.gradient(points_m, axis=-2)
    tang /= np.maximum(np.linalg.norm(tang, axis=-1, keepdims=True), 1e-12)
    return np.stack([-tang[..., 1], tang[..., 0]], axis=-1)


class LoopReplay:
    """The batched loop model fed a recording's inputs.

    Args: data: the loop channels; shape_model: the fast chain; loop_length_m: (F,) the model's loop length per frame.
    Attributes: normals (F, K, 2), phidot_rad_s (F,), simulations (rows evaluated).
    """

    def __init__(self, data: LoopData, shape_model: LoopShapeModel, loop_length_m: np.ndarray) -> None:
        self.data = data
        self.model = shape_model
        self.loop_length_m = np.asarray(loop_length_m, dtype=float)
        self.phidot_rad_s = phidot(data.time_s, data.phi_rad, data.segment)
        self.simulations = 0
        self.normals = outward_normals(self.contours(shape_model.theta0()[None, :])[0])

    def contours(self, theta: np.ndarray) -> np.ndarray:
        """Model contours (B, F, K, 2), metres, table frame."""
        theta = np.atleast_2d(theta)
        d = self.data
        tg = self.model.targets(theta, phi_rad=d.phi_rad, phidot_rad_s=self.phidot_rad_s, speed_mps=d.speed_mps,
                                loop_length_m=self.loop_length_m)
        self.simulations += theta.shape[0]
        return self.model.follow(theta, tg, time_s=d.time_s, segment=d.segment, loop_length_m=self.loop_length_m)

    def set_normals(self, theta_row: np.ndarray) -> None:
        self.normals = outward_normals(self.contours(theta_row[None, :])[0])

    def measured(self) -> dict[str, np.ndarray]:
        """The observed contours along the normals, flattened frame-major (F K,)."""
        return {CHANNEL: np.sum(self.data.points_m * self.normals, axis=-1).reshape(-1)}

    def predict(self, theta: np.ndarray, **_) -> dict[str, np.ndarray]:
        """Model channel (B, F K) for rows theta (B, N_THETA)."""
        c = self.contours(theta)
        return {CHANNEL: np.sum(c * self.normals[None], axis=-1).reshape(c.shape[0], -1)}
