"""Residuals per channel (recording - model) and each channel's noise level estimated from the data itself."""

from __future__ import annotations

import numpy as np

CHANNELS = ("rope_speed_mps", "battery_v")
"""Channels the drive diagnosis compares (motor_rpm is the same encoder as rope_speed_mps: reported, not fitted)."""


def noise_sigma(x: np.ndarray) -> float:
    """Measurement noise of a sampled signal from its second differences (robust to steps and slopes):
    sigma = 1.4826 MAD(x[k+1] - 2 x[k] + x[k-1]) / sqrt(6); floored at the rounding step's 1/sqrt(12)."""
    x = np.asarray(x, dtype=float)
    if x.size < 5:
        return float("nan")
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    mad = np.median(np.abs(d2 - np.median(d2)))
    steps = np.diff(np.unique(np.round(x, 6)))
    lsb = float(steps.min()) if steps.size else 0.0
    return float(max(1.4826 * mad / np.sqrt(6.0), lsb / np.sqrt(12.0), 1e-9))


def effective_fraction(r: np.ndarray) -> float:
    """(1 - rho) / (1 + rho) with rho the lag-1 autocorrelation of r: the share of samples that count as
    independent (AR(1) approximation), in (0, 1]."""
    r = np.asarray(r, dtype=float)
    if r.size < 3:
        return 1.0
    r = r - r.mean()
    den = float(np.dot(r, r))
    if den <= 0.0:
        return 1.0
    rho = float(np.dot(r[1:], r[:-1]) / den)
    rho = min(max(rho, 0.0), 0.98)
    return (1.0 - rho) / (1.0 + rho)


class Residuals:
    """Estimator: fit(data, prediction) computes per-channel residuals_ (S,) and noise_ (sigma per channel,
    from the recorded signal), rms_ per channel."""

    def __init__(self, *, channels: tuple[str, ...] = CHANNELS) -> None:
        self.channels = channels

    def fit(self, data, prediction: dict[str, np.ndarray]) -> Residuals:
        measured = {"rope_speed_mps": data.speed_mps, "battery_v": data.battery_v, "motor_rpm": data.rpm}
        valid = observed(data)
        # an observation that does not observe the channel has residual 0 (and weight 0 in every fit)
        self.residuals_ = {c: np.where(valid[c], measured[c] - prediction[c].reshape(-1), 0.0) for c in self.channels}
        self.noise_ = channel_noise(data)
        self.rms_ = {c: float(np.sqrt(np.mean(self.residuals_[c][valid[c]] ** 2))) for c in self.channels}
        return self


def observed(data) -> dict[str, np.ndarray]:
    """channel -> (S,) bool: the observation observes the channel."""
    return {"rope_speed_mps": np.asarray(data.speed_valid, dtype=bool),
            "motor_rpm": np.asarray(data.speed_valid, dtype=bool),
            "battery_v": np.ones(data.time_s.size, dtype=bool)}


def _measured(data) -> dict[str, np.ndarray]:
    return {"rope_speed_mps": data.speed_mps, "battery_v": data.battery_v, "motor_rpm": data.rpm}


def channel_noise(data) -> dict[str, dict[int, float]]:
    """channel -> {observation kind: sigma}: each kind's noise from its own samples (noise_sigma; each burst and
    the telemetry are separate series, sigma the median over bursts)."""
    out: dict[str, dict[int, float]] = {}
    valid = observed(data)
    meas = _measured(data)
    for c in CHANNELS:
        out[c] = {}
        for k in np.unique(data.kind):
            m = (data.kind == k) & valid[c]
            x = meas[c][m]
            if x.size < 5:
                continue
            t = data.time_s[m]
            # split at gaps (bursts are separate series)
            cuts = np.flatnonzero(np.diff(t) > 5.0 * np.median(np.diff(t))) + 1
            parts = [p for p in np.split(x, cuts) if p.size >= 5]
            out[c][int(k)] = float(np.median([noise_sigma(p) for p in parts])) if parts else noise_sigma(x)
    return out


def channel_weights(data, residuals: dict[str, np.ndarray] | None, noise: dict[str, dict[int, float]], *,
                    fit_mask: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """channel -> (S,) 1 / sigma per observation, 0 where the channel is not observed. sigma per kind: the
    larger of the noise and the residual's robust scale on the fit samples (when residuals are given), plus the
    timing term (sample_sigma, per kind) and the observation's own floor (speed_floor_mps)."""
    valid = observed(data)
    meas = _measured(data)
    out = {}
    for c in CHANNELS:
        sigma = np.full(data.time_s.size, np.inf)
        for k, nk in noise[c].items():
            m = (data.kind == k) & valid[c]
            scale = max(nk, 1e-9)
            if residuals is not None:
                mf = m & (fit_mask if fit_mask is not None else True)
                if mf.sum() > 10:
                    scale = max(scale, robust_scale(residuals[c][mf]))
            if m.sum() >= 2:
                sigma[m] = sample_sigma(data.time_s[m], meas[c][m], scale)
        if c == "rope_speed_mps":
            sigma = np.sqrt(sigma ** 2 + np.asarray(data.speed_floor_mps) ** 2)
        out[c] = np.where(valid[c] & np.isfinite(sigma), 1.0 / sigma, 0.0)
    return out


TIMING_SIGMA_S = 2.5e-3 / np.sqrt(12.0)
"""Timing uncertainty of a sample against the model: the ESC's 400 Hz frame latches at a phase the recording
does not give (uniform over 2.5 ms)."""


def sample_sigma(t_s: np.ndarray, measured: np.ndarray, scale: float | np.ndarray) -> np.ndarray:
    """Per-sample sigma: the channel's residual scale plus the timing uncertainty times the signal's slope,
    sqrt(scale^2 + (TIMING_SIGMA_S dy/dt)^2), the slope taken as the larger one-sided difference."""
    d = np.diff(measured) / np.maximum(np.diff(t_s), 1e-4)
    slope = np.zeros(measured.shape)
    slope[1:] = np.abs(d)
    slope[:-1] = np.maximum(slope[:-1], np.abs(d))
    return np.sqrt(scale ** 2 + (TIMING_SIGMA_S * slope) ** 2)


def robust_scale(r: np.ndarray) -> float:
    """1.4826 x the median absolute deviation (a Gaussian sigma robust to outliers)."""
    return float(1.4826 * np.median(np.abs(r - np.median(r))))
