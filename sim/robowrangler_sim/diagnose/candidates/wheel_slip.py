"""wheel_slip: the rope runs slower than the wheel surface (traction limit of the nip)."""

from __future__ import annotations

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability


class WheelSlip(Candidate):
    effect_id = "wheel_slip"
    law = "v_rope = (1 - s) r omega"
    regime = "high acceleration or load"
    separating_measurement = "rope speed measured on the rope itself (a rope-side encoder or the camera's loop speed)"
    confused_with = ("none",)

    def identifiable(self, data) -> Identifiability:
        return Identifiability(False, "rope_speed_mps is the motor encoder's wheel speed times the radius: slip "
                               "changes nothing the motor encoder, ESC or battery see", self.separating_measurement)
