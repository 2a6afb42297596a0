"""Replay: drive a model (a batch of parameter rows) with the recording's ESC pulses, open loop, on the tick
grid; predictions at the observations (recording_data.DriveData), in the recorded channels' terms.

Rope speed from the encoder (speed_source "encoder"): the model's rope travel between the two edge times the
observation spans, over that time (its position is the integral of its speed, sampled every tick, linear
inside a tick). A record that saw no edge for a while (recording_data.REST_GAP_S: the rope at or near rest)
observes only that the travel since the last edge is short of the next edge: the model is observed through the
same encoder, reading what the recording read while its own travel stays in that interval, and off by as much as
it leaves it (an edge the model passes that the encoder never saw, a model that ran backwards).
From the filtered telemetry (speed_source "filtered"): the model's speed through the firmware's low-pass (its time
constant from /device/params) and the M/T estimate's half-tick delay.
"""

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
        data: the recording's drive observations.
        base_params: the model's DriveParams (its fixed constants: geometry, ESC protocol, battery curve).
    Attributes: consts (kernel constants), theta0 (N_THETA,) the base model's row, simulations (rows simulated).
    """

    def __init__(self, data: DriveData, base_params: DriveParams) -> None:
        self.data = data
        self.base_params = base_params
        tau = data.device_params.get("speed_filter_tau_s", DEFAULT_SPEED_FILTER_TAU_S) + MT_DELAY_S
        self.consts = db.consts_from_params(base_params, meas_tau_s=tau)
        self.theta0 = db.theta_from_params(base_params)
        self.simulations = 0
        self._encoder = data.speed_source == "encoder"
        n_ticks = data.pulse_us.size
        if self._encoder:
            self._ticks = np.arange(n_ticks)  # speed every tick: the position between any two edge times
            e = np.clip(data.edge_ticks, 0.0, n_ticks - 1 - 1e-9)
            self._i0, self._i1 = np.floor(e[:, 0]).astype(np.int64), np.floor(e[:, 1]).astype(np.int64)
            self._f0, self._f1 = e[:, 0] - self._i0, e[:, 1] - self._i1
            self._span_s = np.maximum(e[:, 1] - e[:, 0], 1e-6) * 1e-3
            self._at = data.sample_ticks.clip(max=n_ticks - 1)
            upper = data.speed_upper_mps if data.speed_upper_mps is not None else np.full(data.time_s.size, np.nan)
            self._censored = np.flatnonzero(np.isfinite(upper) & data.speed_valid)
            self._upper = upper[self._censored]
            self._read = data.speed_mps[self._censored]
        else:
            self._ticks, self._at = np.unique(data.sample_ticks, return_inverse=True)

    def predict(self, theta: np.ndarray, *, load_mask: np.ndarray | None = None,
                gate: db.TickGate | None = None) -> dict[str, np.ndarray]:
        """Model channels (B, S) for parameter rows theta (B, N_THETA): rope_speed_mps (observed as the recording
        observes it), motor_rpm, battery_v, true_speed_mps (the model's speed at the observation's tick).
        gate: an effect confined to one regime (drive_batch.TickGate on the replay's tick grid)."""
        theta = np.atleast_2d(theta)
        out = db.simulate_drive_batch(theta, self.consts, self.data.pulse_us, self._ticks,
                                      load_mask=load_mask, gate=gate, latch="box")
        self.simulations += theta.shape[0]
        v = out["rope_speed_mps"]
        if self._encoder:
            x = np.zeros_like(v)
            x[:, 1:] = np.cumsum(0.5 * (v[:, 1:] + v[:, :-1]), axis=1) * 1e-3
            speed = self._edge_speed(x)
        else:
            speed = out["measured_speed_mps"][:, self._at]
        r = self.consts[db.C_R_WHEEL]
        return {"rope_speed_mps": speed, "motor_rpm": speed / r * RAD_S_TO_RPM,
                "battery_v": out["battery_v"][:, self._at], "true_speed_mps": v[:, self._at]}

    def _edge_speed(self, x: np.ndarray) -> np.ndarray:
        """(B, S) mean speed between each observation's edge times of positions x (B, T) per tick (linear inside
        a tick)."""
        x0 = x[:, self._i0] + (x[:, self._i0 + 1] - x[:, self._i0]) * self._f0
        x1 = x[:, self._i1] + (x[:, self._i1 + 1] - x[:, self._i1]) * self._f1
        d = (x1 - x0) / self._span_s
        speed = np.abs(d)
        if self._censored.size:
            # "no edge since": the encoder reads what the recording read while the model's mean speed since the
            # last edge stays in [0, upper] (its travel short of the next edge), off by how far it leaves it
            s = d[:, self._censored]
            speed[:, self._censored] = self._read + (s - np.clip(s, 0.0, self._upper))
        return speed

    def observe(self, position_m: np.ndarray, battery_v: np.ndarray) -> dict[str, np.ndarray]:
        """The recorded channels (S,) of a trajectory given per tick of the replay's grid, from outside the model
        (the diagnose proof's truth plant): position_m, battery_v (T,), tick i at (i - preroll_ticks) ms from the
        first telemetry record. Observed as predict observes the model's own: the mean speed between the recorded
        edge times (position linear inside a tick), the volts at the observation's tick. Encoder recordings only
        (a filtered speed observes the firmware's filter, not a position): ValueError otherwise."""
        if not self._encoder:
            raise ValueError(f"{self.data.path}: speed_source is {self.data.speed_source!r}; observing a trajectory "
                             "needs the encoder's edge times")
        n = self.data.pulse_us.size
        x, b = np.asarray(position_m, dtype=float), np.asarray(battery_v, dtype=float)
        if x.shape != (n,) or b.shape != (n,):
            raise ValueError(f"position_m, battery_v: expected ({n},) per tick of the replay grid, got "
                             f"{x.shape} and {b.shape}")
        speed = self._edge_speed(x[None, :])[0]
        r = self.consts[db.C_R_WHEEL]
        return {"rope_speed_mps": speed, "motor_rpm": speed / r * RAD_S_TO_RPM, "battery_v": b[self._at]}
