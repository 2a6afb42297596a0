"""transient_wave_dynamics: the chain follows a new target shape through a first-order lag (tau = kd/kp = 0.5 s,
every point at once); a moving rope carries a change along itself from the exit (waves at v +- sqrt(T/lambda),
the material itself at v). Law: each point follows the target delayed by s / c, s its arc distance from the exit,
c the wave speed."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import Identifiability, LoopCandidate, rotation_frames
from robowrangler_sim.diagnose.parameters import ParamSpec


class TransientWaveDynamics(LoopCandidate):
    effect_id = "transient_wave_dynamics"
    law = "P(t, s) = P_target(t - s / c): a change travels from the exit along the loop at the wave speed c"
    regime = "transients: the module turning, the speed changing"
    params = (ParamSpec("wave_speed_mps", sm.TH_WAVE_MPS, "m/s", 0.5, 40.0, 5.0),)
    neutral = {sm.TH_WAVE_MPS: 0.0}
    separating_measurement = "a fast module turn filmed at a higher frame rate (the change's travel along the arc)"
    confused_with = ("normal_drag_coefficient",)

    def identifiable(self, replay) -> Identifiability:
        d = replay.data
        dv = np.abs(np.diff(d.speed_mps)) / np.maximum(np.diff(d.time_s), 1e-6)
        if rotation_frames(replay) < 10 and np.sum(dv > 0.5) < 5:
            return Identifiability(False, "no transient: the module never turns and the speed never changes",
                                   "a recording with a module turn or a speed step while the loop flies")
        return Identifiability(True)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[2.0], [5.0], [10.0], [20.0]])
