"""loop_speed_dependence: the loop's shape changes continuously with rope speed; the chain snaps to the tabulated
speed at or below the present one. Law: S(v) = S_snap(v) + g_v [S_lin(v) - S_snap(v)] (S_lin: the table continued in
the loop's weight-to-drag ratio (v* / v)^2, linear in 1 / v^2 between the table's speeds; g_v = 1: that continuation)."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.parameters import ParamSpec


class LoopSpeedDependence(LoopCandidate):
    effect_id = "loop_speed_dependence"
    law = "S(v) = S_snap(v) + g_v [S_lin(v) - S_snap(v)]: the shape between the table's speeds (g_v = 1: linear in 1/v^2)"
    regime = "rope speeds between the shape table's speeds"
    params = (ParamSpec("speed_shape_gain", sm.TH_SPEED_GAIN, "1", 0.0, 2.0, 1.0),)
    neutral = {sm.TH_SPEED_GAIN: 0.0}
    separating_measurement = "steady holds at a tabulated speed and between two tabulated speeds"
    confused_with = ("axial_drag_coefficient",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[0.5], [1.0], [1.5]])
