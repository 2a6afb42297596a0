"""Regime gates: an effect of the library confined to one speed range of the run, as a real fault often is (a
latency that appears at high rpm, a rope that flutters above some speed, a bearing that drags only when slow).

A gate is a condition on the rope's speed, so a fitted model carries it to a new run (the SIL evaluates it on the
plant's speed every tick, sil_effects.py): rope speed at least / below a band edge of regimes.SPEED_BANDS_MPS. On a
recording it is the mask of the replay's ticks where the recorded speed satisfies it. Gates on the transients'
sign were tried and left out: confined to the spin-ups, any law turns into a generic transient correction (a drag
switched off during spin-ups was "found" on an effect-free recording). The gates a diagnosis tries are the few
where the refitted nominal model's residual concentrates (``concentrated``): a gated candidate is one more model,
counted with one parameter more (the gate's choice), judged by the same rule as every other (select.accepted).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_SHARE = 0.05
"""A gate must leave at least this share of the fit samples both in and out (else it is the whole run, or nothing)."""


@dataclass(frozen=True)
class RegimeGate:
    """Where an effect acts: rope speed in [speed_min_mps, speed_max_mps)."""

    speed_min_mps: float = 0.0
    speed_max_mps: float = float("inf")

    @property
    def key(self) -> str:
        if np.isfinite(self.speed_max_mps):
            return f"speed<{self.speed_max_mps:g}"
        return f"speed>={self.speed_min_mps:g}"

    @property
    def description(self) -> str:
        if np.isfinite(self.speed_max_mps):
            return f"only below {self.speed_max_mps:g} m/s"
        return f"only at {self.speed_min_mps:g} m/s and above"

    def on(self, speed_mps):
        """Where the gate is open (rope speeds, array or scalar)."""
        v = np.abs(speed_mps)
        return (v >= self.speed_min_mps) & (v < self.speed_max_mps)

    def to_json(self) -> dict[str, float]:
        """The gate's terms in a model file's effect (only those that restrict)."""
        out: dict[str, float] = {}
        if self.speed_min_mps > 0.0:
            out["gate_speed_min_mps"] = float(self.speed_min_mps)
        if np.isfinite(self.speed_max_mps):
            out["gate_speed_max_mps"] = float(self.speed_max_mps)
        return out

    @classmethod
    def from_json(cls, values: dict[str, float]) -> RegimeGate | None:
        """The gate of a model file's effect terms (None when the effect acts everywhere); ValueError when the
        range is empty or negative."""
        if not any(k in values for k in GATE_TERMS):
            return None
        lo, hi = float(values.get("gate_speed_min_mps", 0.0)), float(values.get("gate_speed_max_mps", float("inf")))
        if not 0.0 <= lo < hi:
            raise ValueError(f"gate_speed_min_mps, gate_speed_max_mps: expected 0 <= min < max, got {lo}, {hi}")
        return cls(lo, hi)


GATE_TERMS = ("gate_speed_min_mps", "gate_speed_max_mps")

GATES: tuple[RegimeGate, ...] = (RegimeGate(speed_min_mps=2.0), RegimeGate(speed_min_mps=5.0),
                                 RegimeGate(speed_min_mps=8.0), RegimeGate(speed_max_mps=2.0))
"""The gates a diagnosis may try: the speed bands' edges (regimes.SPEED_BANDS_MPS)."""


def tick_speed(data) -> np.ndarray:
    """The recorded rope speed on the replay's tick grid (T,) (telemetry, interpolated)."""
    n = data.pulse_us.size
    t_tick = data.tel_time_s[0] + (np.arange(n) - data.preroll_ticks) * 1e-3
    return np.interp(t_tick, data.tel_time_s, data.tel_speed_mps)


def concentrated(gates, on_samples: dict[RegimeGate, np.ndarray], z2: np.ndarray, *, n: int = 2) -> list[RegimeGate]:
    """The n gates that split the mean squared weighted residual z2 most unevenly between their samples and the
    rest, either way (each with at least MIN_SHARE of the samples in and out). Either way, because the refit moves
    what it cannot explain: an effect above 5 m/s that the refit's drag and friction half absorb leaves its
    residual below 5 m/s."""
    scored = []
    for g in gates:
        m = on_samples[g]
        share = m.mean() if m.size else 0.0
        if not MIN_SHARE <= share <= 1.0 - MIN_SHARE:
            continue
        ratio = max(z2[m].mean(), 1e-12) / max(z2[~m].mean(), 1e-12)
        scored.append((abs(np.log(ratio)), g))
    scored.sort(key=lambda x: -x[0])
    return [g for _, g in scored[:n]]
