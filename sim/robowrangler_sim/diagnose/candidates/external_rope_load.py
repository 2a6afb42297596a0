"""external_rope_load: a force on the rope over the located spans (a snag, a hand, an object), F_ext there."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


class ExternalRopeLoad(Candidate):
    effect_id = "external_rope_load"
    law = "F_ext constant over the located spans, 0 elsewhere"
    channels = ("rope_speed_mps", "motor_rpm", "battery_v")
    regime = "the located spans only (loaded)"
    params = (ParamSpec("external_load_n", db.TH_EXT_LOAD, "N", 0.0, 5.0, 0.3),)
    neutral = {db.TH_EXT_LOAD: 0.0}
    separating_measurement = "rope tension at the guide (spindle load) or a camera on the rope during the span"
    confused_with = ("coulomb_friction_n",)
    uses_located_spans = True

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[0.05], [0.2], [0.5], [1.0]])
