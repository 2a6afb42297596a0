"""esc_deadband: zero throttle up to min + w; once stopped, the ESC starts again only above min + w + h."""

from __future__ import annotations

import itertools

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


class EscDeadband(Candidate):
    effect_id = "esc_deadband"
    law = "throttle = 0 for pulse <= min + w (on again above min + w + h), else (pulse - min - w)/(max - min - w)"
    channels = ("rope_speed_mps", "motor_rpm")
    regime = "low throttle: starts from rest and the lowest speed band"
    params = (ParamSpec("deadband_us", db.TH_DEADBAND, "us", 0.0, 150.0, 20.0),
              ParamSpec("hysteresis_us", db.TH_HYST, "us", 0.0, 80.0, 10.0))
    neutral = {db.TH_HYST: 0.0}
    needs_regimes = ("speed_band:rest",)
    gateable = True
    gated_floor = ("deadband_us",)
    separating_measurement = "a slow pulse ramp up from the minimum and back down (throttle sweep at rest)"
    confused_with = ("coulomb_friction_n", "low_speed_friction")

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array(list(itertools.product((10.0, 25.0, 45.0, 70.0), (0.5, 10.0, 25.0))))
