"""tip_bending_stiffness: the rope's bending stiffness B rounds the tip, where the effective tension T - lambda v^2
is small, over the bending length l_b = sqrt(B / T_eff). Law: the tangent angle along the arc smoothed with a
Gaussian of width l_b (per 2 m of loop), the end error spread linearly along the arc."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.parameters import ParamSpec


class TipBendingStiffness(LoopCandidate):
    effect_id = "tip_bending_stiffness"
    law = "tangent angle smoothed over l_b = sqrt(B / T_eff) (Gaussian along the arc, per 2 m of loop)"
    regime = "the tip (highest curvature), at every speed"
    params = (ParamSpec("tip_bending_length_m", sm.TH_BEND_LEN_M, "m", 0.0, 0.4, 0.1),)
    separating_measurement = "contours at several loop lengths (the bending length does not scale with the loop)"
    confused_with = ("axial_drag_coefficient",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[0.03], [0.08], [0.15], [0.25]])
