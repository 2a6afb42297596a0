"""motor_cogging: torque ripple T_cog sin(N_cog theta) at the magnet/slot frequency of the motor."""

from __future__ import annotations

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability

COGGING_PERIODS_PER_REV = 42  # 12 slots x 14 poles: lcm 84 / 2 (23xx outrunner class)


class MotorCogging(Candidate):
    effect_id = "motor_cogging"
    law = "T = T_cog sin(N_cog theta), N_cog = 42 per revolution"
    channels = ("rope_speed_mps", "motor_rpm")
    regime = "slowest speeds, where the ripple is not averaged out"
    separating_measurement = "the raw encoder edge period at 1 kHz (the recordings' burst channel)"

    def identifiable(self, data) -> Identifiability:
        moving = data.tel_speed_mps[data.tel_speed_mps > 0.3]
        if moving.size == 0:
            return Identifiability(False, "the rope never moves", self.separating_measurement)
        f_min = moving.min() / (2 * 3.141592653589793 * 0.015) * COGGING_PERIODS_PER_REV
        if data.bursts:
            return Identifiability(False, f"the ripple (>= {f_min:.0f} Hz at the slowest visited speed) is within the "
                                   f"bursts' 1 kHz only below about 1 m/s, and the batched drive model has no ripple "
                                   f"term yet: not fitted", "burst samples during a slow hold below 1 m/s, and a "
                                   "rippling model")
        return Identifiability(False, f"cogging ripple >= {f_min:.0f} Hz at every visited speed, above the "
                               f"telemetry's {data.telemetry_hz / 2:.0f} Hz Nyquist limit (its mean is zero)",
                               self.separating_measurement)
