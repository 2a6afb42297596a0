"""uniform_wind: a uniform horizontal wind w along the launch direction. The air's velocity relative to the running
rope is w e_x - v t: its axial part changes the skin friction along the rope (a tail wind w > 0 lightens the outgoing
branch's drag and loads the returning one's, a head wind the reverse) and its normal part -w sin(theta) adds a
pressure drag across the rope, largest at the tip. Law: the string's response to that extra load about the table's
shape (diagnose/loop/wind_load.py, the linear system of moving_elastica.py applied in steps). At one speed and phi a
C_f change lifts both branches alike; the wind's is uneven, which is what tells them apart."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.parameters import ParamSpec


class UniformWind(LoopCandidate):
    effect_id = "uniform_wind"
    law = ("the string's response to the load 0.5 rho C_f pi d (|u_t| u_t + v^2) t + 0.5 rho C_n d |u_n| u_n n, "
           "u_t = w t_x - v, u_n = -w sin(theta): the wind's skin friction and normal drag on the running rope")
    regime = "every phi and speed (uneven on the two branches)"
    params = (ParamSpec("wind_speed_mps", sm.TH_WIND_MPS, "m/s", -6.0, 6.0, 1.0),)
    separating_measurement = "the same phi at two headings of the module (wind turns with the world, the table with the module)"
    confused_with = ("phi offset of the inclination sensor",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[-2.0], [-1.0], [1.0], [2.0]])
