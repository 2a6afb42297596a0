"""battery_sag: a polarisation branch in the pack, V_p' = (R_p I - V_p) / tau_p, on top of the series resistance."""

from __future__ import annotations

import itertools

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


class BatterySag(Candidate):
    effect_id = "battery_sag"
    law = "V_batt = V_oc - R_s I - V_p,  tau_p V_p' = R_p I - V_p"
    channels = ("battery_v", "rope_speed_mps")
    regime = "loaded: after current steps (spin-up, high speed)"
    params = (ParamSpec("polarisation_resistance_ohm", db.TH_POL_R, "Ohm", 0.0, 0.3, 0.03),
              ParamSpec("polarisation_time_constant_s", db.TH_POL_TAU, "s", 0.02, 30.0, 1.0))
    neutral = {db.TH_POL_R: 0.0, db.TH_POL_TAU: 1.0}
    needs_regimes = ("motion:accelerating",)
    gateable = True
    gated_floor = ("polarisation_resistance_ohm",)
    separating_measurement = "battery current (a shunt) with the voltage during a load step"
    confused_with = ("battery_internal_resistance_ohm", "battery_open_circuit_v")

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array(list(itertools.product((0.01, 0.03, 0.08), (0.1, 0.5, 2.0, 8.0))))
