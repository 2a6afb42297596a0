"""Residuals on the loop: the observed contour's signed normal distance from the model's (outward positive), per
frame and point, and the camera's contour noise estimated from the data itself."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.residuals import noise_sigma


class LoopResiduals:
    """Estimator: fit(replay, prediction) -> residuals_ (F, K) m, noise_m_ (contour noise per point, 1 sigma),
    rms_m_ (overall), rms_per_point_m_ (K,)."""

    def fit(self, replay, prediction: np.ndarray) -> LoopResiduals:
        data = replay.data
        F, K = data.points_m.shape[:2]
        measured = replay.measured()["contour_normal_m"].reshape(F, K)
        self.residuals_ = measured - np.asarray(prediction).reshape(F, K)
        self.noise_m_ = contour_noise_m(data, replay.normals)
        self.rms_m_ = float(np.sqrt(np.mean(self.residuals_ ** 2)))
        self.rms_per_point_m_ = np.sqrt(np.mean(self.residuals_ ** 2, axis=0))
        return self


def contour_noise_m(data, normals: np.ndarray) -> float:
    """Camera noise along the normal, 1 sigma: frame-to-frame second differences of each point's normal offset
    (robust: the median over points of noise_sigma within each airborne stretch; the loop's own motion at 30 Hz is
    smooth and drops out of the second difference)."""
    proj = np.sum(data.points_m * normals, axis=-1)  # (F, K)
    sig = []
    for s in np.unique(data.segment):
        m = np.flatnonzero(data.segment == s)
        if m.size < 5:
            continue
        for k in range(1, proj.shape[1] - 1):
            sig.append(noise_sigma(proj[m, k]))
    return float(np.median(sig)) if sig else float("nan")
