"""servo_deadband: wheel-mode moving speeds up to d register units do not drive the AX-12A (with hysteresis h)."""

from __future__ import annotations

import itertools

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import spindle_batch as sb


class ServoDeadband(Candidate):
    effect_id = "servo_deadband"
    law = ("u = 0 for |moving speed| <= d (once stopped, drives again only above d + h), else u = moving speed / "
           "1023: the guide stops short where the command is small")
    plant = "spindle"
    channels = ("guide_step_mm", "spindle_load_permille")
    regime = "small spindle commands: the end of every move, slow moves"
    params = (ParamSpec("deadband_raw", sb.SP_DEADBAND_RAW, "raw", 0.0, 300.0, 50.0),
              ParamSpec("hysteresis_raw", sb.SP_HYST_RAW, "raw", 0.0, 150.0, 20.0))
    neutral = {sb.SP_DEADBAND_RAW: 0.0, sb.SP_HYST_RAW: 0.0}
    needs_regimes = ("command:slow",)
    separating_measurement = ("a slow ramp of the moving speed up from 0 and back down (the servo's start and "
                              "stop thresholds); the load at rest tells it from friction")
    confused_with = ("friction_torque_nm",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array(list(itertools.product((10.0, 25.0, 40.0, 60.0, 80.0, 110.0, 150.0, 200.0),
                                               (0.0, 15.0, 40.0))))

    def start_grid(self, theta: np.ndarray) -> tuple[list[int], np.ndarray]:
        # friction also stops small commands: search both together
        frictions = theta[sb.SP_FRICTION_NM] * np.array([0.6, 0.8, 1.0, 1.25])
        grid = np.array([[d, h, f] for d, h in self.start_points(theta) for f in frictions])
        return [sb.SP_DEADBAND_RAW, sb.SP_HYST_RAW, sb.SP_FRICTION_NM], grid
