"""esc_latency: the ESC acts on the pulse of d seconds ago (transport/filter delay beyond the frame latch)."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


class EscLatency(Candidate):
    effect_id = "esc_latency"
    law = "u_esc(t) = u_cmd(t - d)"
    channels = ("rope_speed_mps", "motor_rpm", "battery_v")
    regime = "every speed step: accelerating and decelerating"
    params = (ParamSpec("delay_s", db.TH_LATENCY, "s", 0.0, 0.05, 0.005),)
    neutral = {db.TH_LATENCY: 0.0}
    needs_regimes = ("motion:accelerating", "motion:decelerating")
    gateable = True
    gated_floor = ("delay_s",)
    separating_measurement = "ESC pulse and motor speed at 1 kHz around a step (the recordings' 1 kHz bursts)"
    confused_with = ("esc_lag_s", "inertia_kg_m2")

    def start_grid(self, theta: np.ndarray) -> tuple[list[int], np.ndarray]:
        # delay and the ESC's duty lag trade against each other at telemetry rate: search them together
        lags = theta[db.TH_ESC_LAG] * np.array([0.5, 1.0, 1.8])
        grid = np.array([[d, lag] for d in np.arange(0.0, 0.0405, 0.002) for lag in lags])
        return [db.TH_LATENCY, db.TH_ESC_LAG], grid

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.arange(0.0, 0.0405, 0.0005)[:, None]  # 0.5 ms grid: the loss is bumpy in d (step edges)
