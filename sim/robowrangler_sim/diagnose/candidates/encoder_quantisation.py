"""encoder_quantisation: speed read from whole encoder edges (fewer counts per revolution than configured)."""

from __future__ import annotations

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability


class EncoderQuantisation(Candidate):
    effect_id = "encoder_quantisation"
    law = "v_meas = 2 pi r n_edges / (N_cpr T)"
    regime = "slowest speeds (few edges per tick)"
    separating_measurement = "the raw encoder edge count and period per tick (the recordings' 1 kHz bursts)"

    def identifiable(self, data) -> Identifiability:
        if data.speed_source == "encoder":
            return Identifiability(False, "the diagnosis compares the rope's travel between recorded edge times, which "
                                   "has no quantisation beyond the 1 us edge clock; a wrong counts-per-revolution "
                                   "scales every speed like the motor's kv and is absorbed by the refit",
                                   "a rope-side distance (a marked rope over a known length) against the edge count")
        return Identifiability(False, "the firmware's M/T estimate times whole edges and is low-pass filtered "
                               "before telemetry; the edge granularity is not in the telemetry channels",
                               self.separating_measurement)
