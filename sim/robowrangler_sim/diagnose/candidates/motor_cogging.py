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
        dt = float(data.time_s[1] - data.time_s[0]) if data.time_s.size > 1 else 0.02
        nyquist_hz = 0.5 / max(dt, 1e-6)
        # the ripple's frequency at the slowest visited moving speed
        moving = data.speed_mps[data.speed_mps > 0.3]
        if moving.size == 0:
            return Identifiability(False, "the rope never moves", self.separating_measurement)
        f_min = moving.min() / (2 * 3.141592653589793 * 0.015) * COGGING_PERIODS_PER_REV
        return Identifiability(False, f"cogging ripple >= {f_min:.0f} Hz at every visited speed, above the "
                               f"telemetry's {nyquist_hz:.0f} Hz Nyquist limit (its mean is zero)",
                               self.separating_measurement)
