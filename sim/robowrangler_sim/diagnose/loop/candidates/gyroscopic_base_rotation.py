"""gyroscopic_base_rotation: Coriolis force 2 lambda (omega x v) on the running rope when the module turns. In the
plane (pitching, dphi/dt) it pushes the loop sideways in proportion to v dphi/dt: phi_eff = phi - k_g v dphi/dt
(k_g in s^2/m). Yaw and roll rates are not in the recording (only phi is): their Coriolis part is out of plane."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import Identifiability, LoopCandidate, ROTATING_RAD_S
from robowrangler_sim.diagnose.parameters import ParamSpec

MIN_SPEED_SPREAD_MPS = 1.0


class GyroscopicBaseRotation(LoopCandidate):
    effect_id = "gyroscopic_base_rotation"
    law = "phi_eff = phi - k_g v dphi/dt (Coriolis 2 lambda omega v on the running rope while the module pitches)"
    regime = "while the module turns, growing with rope speed"
    params = (ParamSpec("coriolis_gain_s2_per_m", sm.TH_GYRO_S2_PER_M, "s^2/m", -0.1, 0.3, 0.05),)
    separating_measurement = ("module turns at rope speeds at least 1 m/s apart, and the module's yaw/roll rates "
                              "(IMU or the arm's joint states) in the recording")
    confused_with = ("normal_drag_coefficient",)

    def identifiable(self, replay) -> Identifiability:
        turning = np.abs(replay.phidot_rad_s) > ROTATING_RAD_S
        if turning.sum() < 10:
            return Identifiability(False, "the module never pitches (dphi/dt < 5 deg/s); yaw and roll rates are not "
                                   "recorded", self.separating_measurement)
        v = replay.data.speed_mps[turning]
        if np.ptp(v) < MIN_SPEED_SPREAD_MPS:
            return Identifiability(False, f"the module turns at one rope speed only ({v.min():.1f}-{v.max():.1f} m/s): "
                                   "a Coriolis deflection (grows with v) is then the normal-drag lag",
                                   self.separating_measurement)
        return Identifiability(True)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[-0.03], [0.03], [0.08]])
