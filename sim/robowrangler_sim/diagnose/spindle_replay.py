"""Spindle replay: the batched spindle plant (plants/spindle_batch.py) fed the recording's spindle commands, open
loop, from the first recorded guide position; predictions at the telemetry samples in the recorded channels' terms.

Compared channels (recording - model):
    guide_step_mm           the guide position's change over STEP_SAMPLES samples (0.1 s at 50 Hz): an open-loop
                            integrator drifts, so the position is compared by its short-horizon motion
    spindle_load_permille   the servo's present load
guide_position_mm (the position itself) is reported, not fitted.
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.spindle_data import SpindleData
from robowrangler_sim.plants import spindle_batch as sb
from robowrangler_sim.plants.spindle import SpindleParams

STEP_SAMPLES = 5
CHANNELS = ("guide_step_mm", "spindle_load_permille")


def steps(x: np.ndarray) -> np.ndarray:
    """x[k] - x[k - STEP_SAMPLES] along the last axis (0 for the first STEP_SAMPLES)."""
    out = np.zeros_like(x)
    out[..., STEP_SAMPLES:] = x[..., STEP_SAMPLES:] - x[..., :-STEP_SAMPLES]
    return out


class SpindleReplay:
    """The batched spindle model fed one recording's commands. theta0: the base model's row."""

    def __init__(self, data: SpindleData, base_params: SpindleParams) -> None:
        self.data = data
        self.base_params = base_params
        self.theta0 = sb.theta_from_spindle_params(base_params)
        self.measured = {"guide_step_mm": steps(data.guide_mm), "spindle_load_permille": data.load_permille,
                         "guide_position_mm": data.guide_mm}
        self.simulations = 0

    def predict(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """Model channels (B, S) for parameter rows theta (B, N_SPINDLE_THETA)."""
        theta = np.atleast_2d(theta)
        out = sb.simulate_spindle_batch(theta, self.data.moving_speed_raw, self.data.sample_ticks,
                                        start_position_mm=float(self.data.guide_mm[0]), params=self.base_params)
        self.simulations += theta.shape[0]
        return {"guide_step_mm": steps(out["guide_position_mm"]), "spindle_load_permille": out["load_permille"],
                "guide_position_mm": out["guide_position_mm"]}
