"""uniform_wind: a uniform horizontal wind w along the launch direction. Its normal drag 0.5 rho C_n d w |w| per
metre adds to the weight lambda g: the loop hangs as under a gravity tilted by delta = atan(0.5 rho C_n d w|w| /
(lambda g)) and stronger by 1/cos(delta). Law: shape = R(delta) S(phi - delta, v sqrt(cos delta))."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.parameters import ParamSpec


class UniformWind(LoopCandidate):
    effect_id = "uniform_wind"
    law = "shape = R(delta) S(phi - delta), tan delta = 0.5 rho C_n d w|w| / (lambda g): gravity tilted by the wind"
    regime = "every phi and speed (a rotation of the whole loop)"
    params = (ParamSpec("wind_speed_mps", sm.TH_WIND_MPS, "m/s", -6.0, 6.0, 1.0),)
    separating_measurement = "the same phi at two headings of the module (wind turns with the world, the table with the module)"
    confused_with = ("phi offset of the inclination sensor",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[-2.0], [-1.0], [1.0], [2.0]])
