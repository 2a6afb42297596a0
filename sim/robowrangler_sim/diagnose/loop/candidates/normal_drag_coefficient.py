"""normal_drag_coefficient: normal air drag on the loop swinging with the module: the loop trails the module's
rotation. Law: phi_eff = phi - tau_n dphi/dt, the lag tau_n growing with C_n. It is reported as tau_n itself: the
contours give the lag; turning it into C_n needs a model of how the loop's tension carries the drag, which this
law does not have."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import Identifiability, LoopCandidate, rotation_frames
from robowrangler_sim.diagnose.parameters import ParamSpec


class NormalDragCoefficient(LoopCandidate):
    effect_id = "normal_drag_coefficient"
    law = "phi_eff = phi - tau_n dphi/dt (normal drag on the sideways-moving loop; tau_n grows with C_n)"
    regime = "while the module turns"
    params = (ParamSpec("normal_drag_lag_s", sm.TH_ROT_LAG_S, "s", -0.5, 1.5, 0.2),)
    separating_measurement = "module turns at two or more rope speeds (the Coriolis deflection grows with speed, the drag lag does not)"
    confused_with = ("gyroscopic_base_rotation", "transient_wave_dynamics")

    def identifiable(self, replay) -> Identifiability:
        if rotation_frames(replay) < 10:
            return Identifiability(False, "the module never turns (dphi/dt < 5 deg/s throughout)",
                                   "a recording in which the module pitches (a phi ramp of 10-30 deg/s)")
        return Identifiability(True)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[-0.2], [0.1], [0.3], [0.6]])
