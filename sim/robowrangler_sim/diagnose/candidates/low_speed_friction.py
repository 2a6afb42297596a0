"""low_speed_friction: Stribeck excess friction F_s exp(-(v / v_s)^2) on top of the Coulomb friction."""

from __future__ import annotations

import itertools

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


class LowSpeedFriction(Candidate):
    effect_id = "low_speed_friction"
    law = "F = F_c + F_s exp(-(|v|/v_s)^2)"
    channels = ("rope_speed_mps", "motor_rpm")
    regime = "lowest speed band: breakaway from rest and slow holds"
    params = (ParamSpec("stribeck_force_n", db.TH_STRIBECK_N, "N", 0.0, 3.0, 0.3),
              ParamSpec("stribeck_speed_mps", db.TH_STRIBECK_V, "m/s", 0.05, 3.0, 0.5))
    neutral = {db.TH_STRIBECK_N: 0.0, db.TH_STRIBECK_V: 0.5}
    needs_regimes = ("speed_band:0.3-2 m/s",)
    gateable = True
    gated_floor = ("stribeck_force_n",)
    separating_measurement = "slow steady holds below 1 m/s at several speeds (friction curve)"
    confused_with = ("coulomb_friction_n", "esc_deadband")

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array(list(itertools.product((0.1, 0.3, 0.8), (0.2, 0.5, 1.0, 2.0))))
