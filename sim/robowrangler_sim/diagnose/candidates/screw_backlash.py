"""screw_backlash: lost motion between the servo output (where the position is read) and the lead-screw nut."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import spindle_batch as sb


class ScrewBacklash(Candidate):
    effect_id = "screw_backlash"
    law = ("play operator: the nut follows the servo only once a gap of b mm is taken up; inside the gap the servo "
           "turns without the screw's friction (load ~0, slightly faster)")
    plant = "spindle"
    channels = ("spindle_load_permille", "guide_step_mm")
    regime = "the first b mm after every reversal of the guide's direction"
    params = (ParamSpec("backlash_mm", sb.SP_BACKLASH_MM, "mm", 0.0, 4.0, 0.5),)
    neutral = {sb.SP_BACKLASH_MM: 0.0}
    needs_regimes = ("reversal:yes",)
    separating_measurement = ("the guide's own position (a linear sensor or the loop's length from the camera) "
                              "around reversals; the load dip alone also fits a lower screw friction")
    confused_with = ("friction_torque_nm",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0])[:, None]

    def start_grid(self, theta: np.ndarray) -> tuple[list[int], np.ndarray]:
        # the load dip a gap leaves looks like less screw friction on average: search both together
        frictions = theta[sb.SP_FRICTION_NM] * np.array([0.8, 1.0, 1.25, 1.5, 1.8])
        grid = np.array([[b, f] for b in self.start_points(theta)[:, 0] for f in frictions])
        return [sb.SP_BACKLASH_MM, sb.SP_FRICTION_NM], grid
