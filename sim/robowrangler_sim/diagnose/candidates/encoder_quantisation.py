"""encoder_quantisation: speed read from whole encoder edges (fewer counts per revolution than configured)."""

from __future__ import annotations

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability


class EncoderQuantisation(Candidate):
    effect_id = "encoder_quantisation"
    law = "v_meas = 2 pi r n_edges / (N_cpr T)"
    regime = "slowest speeds (few edges per tick)"
    separating_measurement = "the raw encoder edge count and period per tick (the recordings' 1 kHz bursts)"

    def identifiable(self, data) -> Identifiability:
        return Identifiability(False, "the firmware's M/T estimate times whole edges and is low-pass filtered "
                               "before telemetry; the edge granularity is not in the 50 Hz channels",
                               self.separating_measurement)
