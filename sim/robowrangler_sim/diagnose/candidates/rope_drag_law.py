"""rope_drag_law: air drag on the running rope as a power law F = k v_ref^2 (|v| / v_ref)^n (nominal: n = 2)."""

from __future__ import annotations

import itertools

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


class RopeDragLaw(Candidate):
    effect_id = "rope_drag_law"
    law = "F_drag = k v_ref^2 (|v|/v_ref)^n, v_ref = 4 m/s (nominal n = 2)"
    channels = ("rope_speed_mps", "motor_rpm")
    regime = "grows with speed: the high speed bands"
    params = (ParamSpec("rope_drag_coeff_n_s2_per_m2", db.TH_DRAG_K, "N s^2/m^2", 1e-5, 0.05, 1e-3),
              ParamSpec("drag_exponent", db.TH_DRAG_EXP, "1", 0.5, 4.0, 2.0))
    neutral = {db.TH_DRAG_EXP: 2.0}
    needs_regimes = ("speed_band:5-8 m/s", "speed_band:> 8 m/s")
    gateable = True
    separating_measurement = "steady holds at several well-spaced speeds (speed sweep), or rope tension at the guide"
    confused_with = ("viscous_friction_n_s_per_m", "low_speed_friction")

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        k0 = theta[db.TH_DRAG_K]
        return np.array([[k0 * f, n] for f, n in itertools.product((0.5, 2.0, 8.0, 30.0), (1.0, 1.5, 2.5, 3.0))])
