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
        self.residuals_ = {c: measured[c] - prediction[c].reshape(-1) for c in self.channels}
        self.noise_ = {c: noise_sigma(measured[c]) for c in self.channels}
        self.rms_ = {c: float(np.sqrt(np.mean(self.residuals_[c] ** 2))) for c in self.channels}
        return self


TIMING_SIGMA_S = 2.5e-3 / np.sqrt(12.0)
"""Timing uncertainty of a sample against the model: the ESC's 400 Hz frame latches at a phase the recording
does not give (uniform over 2.5 ms)."""


def sample_sigma(t_s: np.ndarray, measured: np.ndarray, scale: float) -> np.ndarray:
    """Per-sample sigma: the channel's residual scale plus the timing uncertainty times the signal's slope,
    sqrt(scale^2 + (TIMING_SIGMA_S dy/dt)^2), the slope taken as the larger one-sided difference."""
    d = np.diff(measured) / np.diff(t_s)
    slope = np.zeros(measured.shape)
    slope[1:] = np.abs(d)
    slope[:-1] = np.maximum(slope[:-1], np.abs(d))
    return np.sqrt(scale ** 2 + (TIMING_SIGMA_S * slope) ** 2)


def robust_scale(r: np.ndarray) -> float:
    """1.4826 x the median absolute deviation (a Gaussian sigma robust to outliers)."""
    return float(1.4826 * np.median(np.abs(r - np.median(r))))
