"""Replay: drive a model (a batch of parameter rows) with the recording's ESC pulses, open loop, on the tick
grid; predictions at the telemetry samples, in the recorded channels' terms."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.recording_data import DriveData
from robowrangler_sim.plants import DriveParams
from robowrangler_sim.plants import drive_batch as db

RAD_S_TO_RPM = 60.0 / (2.0 * np.pi)
DEFAULT_SPEED_FILTER_TAU_S = 0.01
MT_DELAY_S = 0.0005  # the M/T estimate is the mean speed over the last edge interval: about half a tick late


class DriveReplay:
    """The batched drive model fed the recording's inputs.

    Args:
        data: the recording's drive channels.
        base_params: the model's DriveParams (its fixed constants: geometry, ESC protocol, battery curve).
    Attributes: consts (kernel constants), theta0 (N_THETA,) the base model's row.
    """

    def __init__(self, data: DriveData, base_params: DriveParams) -> None:
        self.data = data
        self.base_params = base_params
        tau = data.device_params.get("speed_filter_tau_s", DEFAULT_SPEED_FILTER_TAU_S) + MT_DELAY_S
        self.consts = db.consts_from_params(base_params, meas_tau_s=tau)
        self.theta0 = db.theta_from_params(base_params)
        self.simulations = 0

    def predict(self, theta: np.ndarray, *, load_mask: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Model channels (B, S) for parameter rows theta (B, N_THETA): rope_speed_mps (measured as the
        firmware does), motor_rpm, battery_v."""
        theta = np.atleast_2d(theta)
        out = db.simulate_drive_batch(theta, self.consts, self.data.pulse_us, self.data.sample_ticks,
                                      load_mask=load_mask, latch="box")
        self.simulations += theta.shape[0]
        speed = out["measured_speed_mps"]
        r = self.consts[db.C_R_WHEEL]
        return {"rope_speed_mps": speed, "motor_rpm": speed / r * RAD_S_TO_RPM, "battery_v": out["battery_v"],
                "true_speed_mps": out["rope_speed_mps"]}
